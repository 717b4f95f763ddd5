//! Lattice numbers of a flow at a level: grid size, relaxation time, Mach number, and the node
//! ranges of refined patches; refusals of what cannot run (tau too close to 1/2, grids too small
//! or too large).

use serde::{Deserialize, Serialize};

use hgym_solvers::lbm::d3::Patch3;
use hgym_solvers::lbm::{Collision, Patch, Units};

use super::{BoundaryKind, DomainSpec, FlowError, FlowSetup, Level, SpanSpec};

/// Largest lattice speed anywhere on the inlet (Mach 0.3 = 0.173 lattice units): above it the
/// compressibility error of the LBM exceeds a few percent.
pub const MAX_LATTICE_SPEED: f64 = 0.173;
/// Largest grid accepted (nodes), about 3.6 GB of populations.
pub const MAX_NODES: usize = 50_000_000;
/// Bytes of populations per node: nine f32 values, in two copies.
pub const BYTES_PER_NODE: usize = 72;

/// Memory this machine can still hand out (`MemAvailable` of `/proc/meminfo`), in bytes; `None`
/// where that cannot be read (then only [`MAX_NODES`] bounds a grid).
pub fn available_memory() -> Option<f64> {
    mem_available(&std::fs::read_to_string("/proc/meminfo").ok()?)
}

/// The `MemAvailable:` line of a `/proc/meminfo` text (kB), in bytes.
fn mem_available(meminfo: &str) -> Option<f64> {
    let line = meminfo.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0)
}

/// Refuses a grid of `cells` whose populations (`need` bytes, `bytes` per cell) exceed the
/// fixed limit ([`MAX_NODES`] D2Q9 cells' worth) or the memory the machine has `available`,
/// naming the limit that binds. Compared as floats: a huge domain must not wrap when cast to
/// `usize`, and a NaN size is refused.
/// `need` is the bytes of the whole grid, held by `ranks` processes in equal shares (a 3D box
/// split over MPI ranks; 1 otherwise): each share must fit.
fn fits_in_memory(cells: &str, need: f64, bytes: usize, ranks: usize, available: Option<f64>) -> Result<(), FlowError> {
    let max_bytes = (MAX_NODES * BYTES_PER_NODE) as f64;
    let share = need / ranks.max(1) as f64;
    let per_rank = if ranks > 1 {
        format!(" per rank of {ranks}")
    } else {
        String::new()
    };
    let message = if !(share <= max_bytes) {
        format!(
            "{cells} cells would need {} GB of populations{per_rank} ({bytes} bytes per cell); the limit is {} cells ({:.1} GB) per process: use a coarser level, a smaller domain or more ranks",
            count(share / 1e9),
            (max_bytes as usize) / bytes,
            max_bytes / 1e9
        )
    } else if let Some(have) = available.filter(|&have| share > have) {
        format!(
            "{cells} cells need {:.1} GB of populations{per_rank}, more than the {:.1} GB this machine has available; \
             use a coarser level, a smaller domain, more ranks or a machine with more memory",
            share / 1e9,
            have / 1e9
        )
    } else {
        return Ok(());
    };
    Err(FlowError::Invalid {
        field: "resolution",
        message,
    })
}

/// A cell count as digits while it is readable, else in scientific notation.
fn count(v: f64) -> String {
    if v < 1e9 {
        format!("{v:.0}")
    } else {
        format!("{v:.3e}")
    }
}

/// Nested refined regions, coarsest first, in reference lengths: rectangles `[x0, x1, y0, y1]`
/// in 2D, boxes `[x0, x1, y0, y1, z0, z1]` in 3D. Inside the first the grid is twice as fine as
/// the level's (`cells_per_length` applies outside), inside the second four times, and so on.
/// Each lies inside the one before; the last contains every body with some room; the first
/// stays clear of the domain's edges and absorbing layers. Along a periodic span a box may cover
/// the whole span instead (`z0`, `z1` at or beyond its ends: a body extruded along it), and a box
/// inside one that does may too.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RefinementSpec {
    pub regions: Vec<Vec<f64>>,
}

impl RefinementSpec {
    /// Every region a proper rectangle (a box with a span) strictly inside the domain or the
    /// region before it, or covering a periodic span whole.
    pub fn check(&self, d: &DomainSpec, span: Option<&SpanSpec>) -> Result<(), FlowError> {
        let z = span.map(|s| s.z);
        let periodic_span = span.is_some_and(|s| s.boundary == BoundaryKind::Periodic);
        let bad = |message: String| FlowError::Invalid {
            field: "refinement.regions",
            message,
        };
        let form = if z.is_some() {
            "[x0, x1, y0, y1, z0, z1]"
        } else {
            "[x0, x1, y0, y1]"
        };
        if self.regions.is_empty() {
            return Err(bad(format!("list at least one region {form}")));
        }
        let mut outer = vec![d.x[0], d.x[1], d.y[0], d.y[1]];
        outer.extend(z.iter().flatten());
        // Whether the outer region covers the periodic span (the domain does).
        let mut wraps = periodic_span;
        for (k, region) in self.regions.iter().enumerate() {
            let proper = region.len() == outer.len() && region.iter().all(|v| v.is_finite()) && region.chunks(2).all(|r| r[0] < r[1]);
            if !proper {
                return Err(bad(format!(
                    "region {} must be {form} with each low end below its high end, got {region:?}",
                    k + 1
                )));
            }
            let covers = wraps && region[4] <= outer[4] && region[5] >= outer[5];
            let inside = |a: usize| region[2 * a] > outer[2 * a] && region[2 * a + 1] < outer[2 * a + 1];
            if !(0..outer.len() / 2).all(|a| inside(a) || (a == 2 && covers)) {
                return Err(bad(format!(
                    "region {} {region:?} must lie inside {} {outer:?} with room to spare{}",
                    k + 1,
                    if k == 0 { "the domain".to_string() } else { format!("region {k}") },
                    if wraps { ", or cover the periodic span whole along z" } else { "" }
                )));
            }
            // A box over the span keeps the span's ends as the next one's bounds along z.
            outer.clone_from(region);
            if let (true, Some(z)) = (covers, z) {
                outer[4..].copy_from_slice(&z);
            }
            wraps = covers;
        }
        Ok(())
    }
}

/// Lattice numbers of the nested patches: each in the node indices of the grid it refines
/// (ranges inclusive; `patches` in 2D, `boxes` in 3D), and the finest grid's cells per length and
/// relaxation time (`tau_l - 1/2 = 2^l (tau - 1/2)`).
#[derive(Clone, Debug, Serialize)]
pub struct RefinementPlan {
    pub patches: Vec<Patch>,
    pub boxes: Vec<Patch3>,
    pub cells_per_length: f64,
    pub tau: f64,
    /// Nodes of the finer levels together (for the memory check).
    pub fine_nodes: usize,
}

/// Lattice numbers of a flow at one level.
#[derive(Clone, Debug, Serialize)]
pub struct FlowPlan {
    pub level: Level,
    pub units: Units,
    pub nx: usize,
    pub ny: usize,
    /// Nodes along the span of a 3D flow (`None` in 2D).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nz: Option<usize>,
    /// Bytes of populations per node (two copies of Q f32 values).
    pub bytes_per_node: usize,
    /// Grid spacing in the set-up's length units (`L / cells_per_length`).
    pub dx: f64,
    pub tau: f64,
    pub mach: f64,
    pub collision: Collision,
    /// The nested patches, if the set-up has refinement regions.
    pub refinement: Option<RefinementPlan>,
}

impl FlowPlan {
    /// One line for people: the grid, its memory, tau and Mach.
    pub fn describe(&self) -> String {
        let cells = (self.nx * self.ny * self.nz.unwrap_or(1)) as f64;
        let grid = match self.nz {
            Some(nz) => format!("{} x {} x {nz}", self.nx, self.ny),
            None => format!("{} x {}", self.nx, self.ny),
        };
        format!(
            "{grid} nodes ({:.2} million, {:.2} GB of populations), {} cells per L, tau {:.4}, Mach {:.3}, {}",
            cells / 1e6,
            cells * self.bytes_per_node as f64 / 1e9,
            self.units.cells_per_length,
            self.tau,
            self.mach,
            self.collision.name()
        )
    }
}

impl FlowSetup {
    /// The lattice numbers at `level`: `n` cells per reference length L, `tau` from Re, U and
    /// `n`; refused when `tau - 1/2` is below the collision operator's margin, or the grid is
    /// smaller than 8 x 8 or larger than [`MAX_NODES`].
    pub fn plan(&self, level: Level) -> Result<FlowPlan, FlowError> {
        let l = self.reference_length();
        let n = self.resolution.at(level) as f64;
        let units = Units {
            cells_per_length: n,
            u_lattice: self.lattice_velocity,
            reynolds: self.reynolds,
        };
        let tau = units.tau();
        let margin = self.collision.min_tau_margin();
        if tau - 0.5 < margin {
            let n_min = (margin * self.reynolds / (3.0 * self.lattice_velocity)).ceil();
            return Err(FlowError::Invalid {
                field: "resolution",
                message: format!(
                    "at the {} level ({n} cells per length) tau = {tau:.5} is too close to 1/2 for the {} collision \
                     (tau - 1/2 must be >= {margin}); use at least {n_min} cells per length, a larger lattice_velocity, \
                     or collision = \"regularized\"",
                    level.name(),
                    self.collision.name()
                ),
            });
        }
        let d = &self.domain;
        let nx_f = (d.x[1] - d.x[0]) * n / l;
        let ny_f = (d.y[1] - d.y[0]) * n / l;
        let nz = match &self.span {
            Some(span) => Some(span.nodes(n / l, level.name())?),
            None => None,
        };
        let bytes = self.span.as_ref().map_or(BYTES_PER_NODE, |s| s.lattice.bytes_per_node());
        let nz_f = nz.unwrap_or(1) as f64;
        let cells = match nz {
            Some(nz) => format!("{} x {} x {nz}", count(nx_f), count(ny_f)),
            None => format!("{} x {}", count(nx_f), count(ny_f)),
        };
        // A uniform grid or box is split over the MPI ranks (`flow::ranks`); a refined one runs
        // whole on each.
        let ranks = if self.refinement.is_none() { super::ranks::rank().1 } else { 1 };
        fits_in_memory(&cells, nx_f * ny_f * nz_f * bytes as f64, bytes, ranks, available_memory())?;
        let (nx, ny) = (nx_f.round() as usize, ny_f.round() as usize);
        if nx < 8 || ny < 8 {
            return Err(FlowError::Invalid {
                field: "domain",
                message: format!("{nx} x {ny} cells is too small; enlarge the domain or the resolution"),
            });
        }
        if self.span.is_none() && nx * ny > MAX_NODES {
            return Err(FlowError::Invalid {
                field: "resolution",
                message: format!(
                    "{nx} x {ny} = {} cells exceeds the limit of {MAX_NODES}; use a coarser level or a smaller domain",
                    nx * ny
                ),
            });
        }
        // Cell-centred nodes: level-0 node i sits at x0 + (i + 1/2) dx; a patch takes the nodes
        // of the grid it refines that cover its region, and its own node 0 sits on the first.
        // A box covering a periodic span takes every node along it (0..=n - 1, as `Refined3`
        // reads it) and its grid wraps there with 2 n nodes.
        let refinement = self.refinement.as_ref().map(|rf| {
            let mut origin = vec![d.x[0] + 0.5 * l / n, d.y[0] + 0.5 * l / n];
            let mut size = vec![nx, ny];
            let mut wraps = vec![false, false];
            if let (Some(span), Some(nz)) = (&self.span, nz) {
                origin.push(span.z[0] + 0.5 * l / n);
                size.push(nz);
                wraps.push(span.boundary == BoundaryKind::Periodic);
            }
            let mut dx = l / n;
            let mut ranges: Vec<Vec<[usize; 2]>> = Vec::new();
            let mut fine_nodes = 0;
            for region in &rf.regions {
                let range: Vec<[usize; 2]> = (0..size.len())
                    .map(|a| {
                        let at = |v: f64, round: fn(f64) -> f64| (round((v - origin[a]) / dx).max(0.0) as usize).min(size[a] - 1);
                        [at(region[2 * a], f64::floor), at(region[2 * a + 1], f64::ceil)]
                    })
                    .collect();
                for (a, r) in range.iter().enumerate() {
                    origin[a] += r[0] as f64 * dx;
                    wraps[a] = wraps[a] && r[0] == 0 && r[1] + 1 == size[a];
                    size[a] = if wraps[a] { 2 * size[a] } else { 2 * (r[1] - r[0]) + 1 };
                }
                fine_nodes += size.iter().product::<usize>();
                dx *= 0.5;
                ranges.push(range);
            }
            let (patches, boxes) = if nz.is_some() {
                let boxes = ranges
                    .iter()
                    .map(|r| Patch3 {
                        lo: [r[0][0], r[1][0], r[2][0]],
                        hi: [r[0][1], r[1][1], r[2][1]],
                    })
                    .collect();
                (vec![], boxes)
            } else {
                let patches = ranges.iter().map(|r| Patch { x: r[0], y: r[1] }).collect();
                (patches, vec![])
            };
            let scale = (1u64 << ranges.len()) as f64;
            RefinementPlan {
                patches,
                boxes,
                cells_per_length: scale * n,
                tau: 0.5 + scale * (tau - 0.5),
                fine_nodes,
            }
        });
        if let (Some(r), Some(nz)) = (&refinement, nz) {
            // A refined box runs whole on each rank, its finer levels beside it.
            let total = (nx * ny * nz + r.fine_nodes) as f64;
            fits_in_memory(
                &format!("{cells} + {} refined", r.fine_nodes),
                total * bytes as f64,
                bytes,
                1,
                available_memory(),
            )?;
        }
        Ok(FlowPlan {
            level,
            units,
            nx,
            ny,
            nz,
            bytes_per_node: bytes,
            dx: l / n,
            tau,
            mach: units.mach(),
            collision: self.collision,
            refinement,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_mem_available_from_meminfo() {
        let text = "MemTotal:       24598416 kB\nMemFree:         1000000 kB\nMemAvailable:   20000000 kB\n";
        assert_eq!(mem_available(text), Some(20_000_000.0 * 1024.0));
        assert_eq!(mem_available("MemTotal: 5 kB\n"), None);
        assert_eq!(mem_available("MemAvailable: lots kB\n"), None);
    }

    /// A grid larger than the machine's available memory is refused naming the field and both
    /// sizes; one that fits, or a machine whose memory cannot be read, passes.
    #[test]
    fn refuses_grids_beyond_the_available_memory() {
        let err = fits_in_memory("320 x 192 x 192", 1.8e9, 152, 1, Some(1.0e9))
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("`resolution`"), "{err}");
        assert!(err.contains("1.8 GB") && err.contains("1.0 GB"), "{err}");
        assert!(fits_in_memory("320 x 192 x 192", 1.8e9, 152, 1, Some(2.0e9)).is_ok());
        assert!(fits_in_memory("320 x 192 x 192", 1.8e9, 152, 1, None).is_ok());
        // Split over 2 ranks, each holds half.
        assert!(fits_in_memory("320 x 192 x 192", 1.8e9, 152, 2, Some(1.0e9)).is_ok());
        let err = fits_in_memory("320 x 192 x 192", 1.8e9, 152, 2, Some(0.5e9))
            .unwrap_err()
            .to_string();
        assert!(err.contains("0.9 GB of populations per rank of 2"), "{err}");
    }
}
