//! A wall that passes through a row of nodes is one wall: every node on it is solid, whatever the
//! rounding of the node positions `origin + i dx` (see `lbm::ON_WALL`).
//!
//! The case is the one that exposed it: a square of side 1 on a 24-cells-per-side grid whose
//! node positions put all four faces on nodes (the square shifted by half a cell from the
//! validation cases, or any refined patch around it: the fine nodes fall on the coarse cell faces).
//! Before the margin, 71 of the 96 face nodes computed `sdf <= 0` and were solid, the other 25 fluid
//! with clamped `q = 1e-3` links, and the Re 200 wake (St, C_D, C_L') was 0.1633, 1.443, 0.361 with
//! one patch origin and 0.1488, 1.560, 0.472 with another.

use std::sync::Arc;

use hgym_solvers::geometry::{Rectangle, Shape};
use hgym_solvers::lbm::{D2q9, D2q9Config, Grid, Side, Sides, ON_WALL};

#[test]
fn every_node_on_a_face_is_solid() {
    let n = 24usize;
    let dx = 1.0 / n as f64;
    // The grid square_re200 had until stop 30 ([0, 60] x [-20, 20], cell-centred nodes), cut at
    // x = 23 to keep the test small: the node positions near the square are the same floats.
    let (nx, ny) = (23 * n, 40 * n);
    let sides = Sides {
        west: Side::Periodic,
        east: Side::Periodic,
        south: Side::Periodic,
        north: Side::Periodic,
    };
    let mut cfg = D2q9Config::new(nx, ny, 0.55, sides);
    cfg.grid = Grid {
        origin: [0.5 * dx, -20.0 + 0.5 * dx],
        dx,
    };
    let square = Rectangle {
        center: [20.0 + 0.5 * dx, 0.5 * dx],
        size: [1.0, 1.0],
    };
    // The rounding really splits the faces: some face nodes lie just outside the square.
    let (mut on_face, mut outside) = (0, 0);
    for y in 0..ny {
        for x in 0..nx {
            let d = square.sdf(cfg.grid.position(x as f64, y as f64));
            if d.abs() <= ON_WALL * dx {
                on_face += 1;
                outside += usize::from(d > 0.0);
            }
        }
    }
    assert_eq!(on_face, 4 * n, "the faces pass through 4 x 24 nodes");
    assert!(outside > 0, "no face node rounds outside: the test would not test the margin");

    let body: Arc<dyn Shape> = Arc::new(square.clone());
    let lbm = D2q9::new(cfg.clone(), vec![body]).expect("builds");
    let mut solid = 0;
    for y in 0..ny {
        for x in 0..nx {
            let d = square.sdf(cfg.grid.position(x as f64, y as f64));
            if d <= ON_WALL * dx {
                assert!(lbm.is_solid(x, y), "node ({x}, {y}) at sdf {d:e} is on or in the square but fluid");
            }
            solid += usize::from(lbm.is_solid(x, y));
        }
    }
    // Faces on nodes: 25 x 25 nodes from face to face, inclusive.
    assert_eq!(solid, (n + 1) * (n + 1), "solid nodes");
}
