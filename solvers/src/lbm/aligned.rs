//! A float array whose first element sits on a 64-byte boundary (a cache line), so that rows
//! whose length is a multiple of 8 floats start on 32-byte boundaries and can be written with
//! aligned non-temporal vector stores.

use std::ops::{Deref, DerefMut};

pub(crate) struct AlignedVec {
    data: Vec<f32>,
    off: usize,
    len: usize,
    pad: usize,
}

impl AlignedVec {
    pub fn zeros(len: usize) -> Self {
        Self::zeros_padded(len, 0)
    }

    /// `len` values with `pad` zeros before and after them that [`AlignedVec::padded`] exposes
    /// (kernels that read a little past a row's ends without a bounds branch).
    pub fn zeros_padded(len: usize, pad: usize) -> Self {
        let data = vec![0.0f32; len + 2 * pad + 16];
        advise_huge_pages(&data);
        // `data` is 4-byte aligned, so the distance from `data[pad]` to the next 64-byte boundary
        // is a multiple of 4 bytes, i.e. a whole number of floats, at most 15.
        let off = pad + ((64 - data[pad..].as_ptr() as usize % 64) % 64) / 4;
        AlignedVec { data, off, len, pad }
    }

    /// The values with their padding: element `k` of the vector is element `k + pad` here.
    pub fn padded(&self) -> &[f32] {
        &self.data[self.off - self.pad..self.off + self.len + self.pad]
    }
}

/// Arrays at least this large (bytes) ask for transparent huge pages.
const HUGE_PAGES_ABOVE: usize = 16 << 20;

/// Asks the kernel to back `data` with 2 MB pages where it can (`madvise(MADV_HUGEPAGE)`, Linux;
/// a hint: nothing changes if transparent huge pages are off or memory is fragmented). A
/// stream-collide step runs 2 Q streams through arrays far larger than the caches; on 4 KB
/// pages each stream crosses a page (a TLB miss, and the hardware prefetcher's stop) every
/// 1024 floats. `vec!` of zeros maps fresh pages only when they are first written, which is
/// after this call.
pub fn advise_huge_pages(data: &[f32]) {
    #[cfg(target_os = "linux")]
    if std::mem::size_of_val(data) >= HUGE_PAGES_ABOVE {
        const PAGE: usize = 2 << 20;
        let start = (data.as_ptr() as usize).next_multiple_of(PAGE);
        let end = data.as_ptr() as usize + std::mem::size_of_val(data);
        if end > start {
            let len = (end - start) / PAGE * PAGE;
            // SAFETY: `[start, start + len)` lies inside `data`'s allocation, which this
            // process owns; MADV_HUGEPAGE changes how its pages are backed, never their
            // contents, and a failure (an old kernel, THP off) is ignored, as a hint may be.
            unsafe { libc::madvise(start as *mut libc::c_void, len, libc::MADV_HUGEPAGE) };
        }
    }
}

impl Deref for AlignedVec {
    type Target = [f32];
    fn deref(&self) -> &[f32] {
        &self.data[self.off..self.off + self.len]
    }
}

impl DerefMut for AlignedVec {
    fn deref_mut(&mut self) -> &mut [f32] {
        &mut self.data[self.off..self.off + self.len]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_on_a_cache_line() {
        for len in [1, 7, 100, 4096] {
            let v = AlignedVec::zeros(len);
            assert_eq!(v.as_ptr() as usize % 64, 0);
            assert_eq!(v.len(), len);
            let p = AlignedVec::zeros_padded(len, 16);
            assert_eq!(p.as_ptr() as usize % 64, 0);
            assert_eq!(p.padded().len(), len + 32);
            assert_eq!(p.padded()[16..].as_ptr(), p.as_ptr());
        }
    }

    /// `AnonHugePages` of this process, kB (`/proc/self/smaps_rollup`).
    fn anon_huge_kb() -> Option<u64> {
        let s = std::fs::read_to_string("/proc/self/smaps_rollup").ok()?;
        let line = s.lines().find(|l| l.starts_with("AnonHugePages:"))?;
        line.split_whitespace().nth(1)?.parse().ok()
    }

    /// A large array keeps its values and, where the kernel offers transparent huge pages on
    /// request, gets them.
    #[test]
    fn large_arrays_get_huge_pages() {
        let before = anon_huge_kb();
        let mut v = AlignedVec::zeros(16 << 20);
        for (k, x) in v.iter_mut().enumerate() {
            *x = k as f32;
        }
        assert!(v.iter().enumerate().all(|(k, x)| *x == k as f32));
        let offered = std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/enabled")
            .is_ok_and(|m| m.contains("[always]") || m.contains("[madvise]"));
        match (offered, before, anon_huge_kb()) {
            (true, Some(a), Some(b)) => assert!(b >= a + 2048, "no huge pages: AnonHugePages {a} -> {b} kB"),
            _ => eprintln!("transparent huge pages not offered here: only the values are checked"),
        }
    }
}
