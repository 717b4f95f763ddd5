//! The nodes of each grid row that need the general path, stored row by row (compressed rows).

/// A node that needs the general path.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Special {
    pub x: u32,
    pub solid: bool,
    /// Range of this node's links in the link list.
    pub link_start: u32,
    pub link_end: u32,
}

/// The specials of every row in row order: row `r` holds `list[start[r] .. start[r + 1]]`, and a
/// special's number (its index in `list`) keys per-special tables such as the 3D face pulls.
#[derive(Debug)]
pub(crate) struct RowSpecials {
    list: Vec<Special>,
    start: Vec<u32>,
}

impl RowSpecials {
    /// An empty list with room for `rows` rows; build it with [`Self::begin_row`] and
    /// [`Self::push`], then [`Self::finish`].
    pub fn with_rows(rows: usize) -> Self {
        Self {
            list: Vec::new(),
            start: Vec::with_capacity(rows + 1),
        }
    }

    /// Starts the next row: the specials pushed from now on belong to it.
    pub fn begin_row(&mut self) {
        self.start.push(self.list.len() as u32);
    }

    pub fn push(&mut self, special: Special) {
        self.list.push(special);
    }

    /// Closes the last row.
    pub fn finish(&mut self) {
        self.begin_row();
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// Number of specials over all rows.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// Every special, in row order (a special's number is its index here).
    pub fn list(&self) -> &[Special] {
        &self.list
    }

    /// The row of special number `j`.
    pub fn row_of(&self, j: usize) -> usize {
        self.start.partition_point(|&s| s as usize <= j) - 1
    }

    /// The specials of row `r`, and the number of the first of them.
    #[inline(always)]
    pub fn row(&self, r: usize) -> (usize, &[Special]) {
        let first = self.start[r] as usize;
        (first, &self.list[first..self.start[r + 1] as usize])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(x: u32) -> Special {
        Special {
            x,
            solid: false,
            link_start: 0,
            link_end: 0,
        }
    }

    #[test]
    fn rows_keep_their_specials_and_numbers() {
        let mut s = RowSpecials::with_rows(3);
        s.begin_row();
        s.push(at(0));
        s.push(at(7));
        s.begin_row();
        s.begin_row();
        s.push(at(3));
        s.finish();
        assert_eq!((s.rows(), s.len()), (3, 3));
        let xs = |r: usize| (s.row(r).0, s.row(r).1.iter().map(|sp| sp.x).collect::<Vec<_>>());
        assert_eq!(xs(0), (0, vec![0, 7]));
        assert_eq!(xs(1), (2, vec![]));
        assert_eq!(xs(2), (2, vec![3]));
        assert_eq!((0..3).map(|j| s.row_of(j)).collect::<Vec<_>>(), [0, 0, 2]);
    }
}
