//! The third dimension of a flow: its span along z and how it is cut into segments, and the 3D
//! solver a set-up with a span builds ([`LbmFlow3`]).
//!
//! A 2D body (circle, square, aerofoil, each pinball cylinder) is extruded along the whole span;
//! spheres and cubes are bodies of their own. The box's x and y faces are the set-up's
//! `boundaries` (west, east, south, north); the two z faces are the span's `boundary`.

use serde::{Deserialize, Serialize};

use hgym_solvers::geometry::{Cuboid, Extruded, Solid, Sphere, StenosedPipe};
use hgym_solvers::lbm::d3::{D3Config, D3q19, D3q27, Face, Faces, Grid3, Lattice3, Lbm3, Refined3, Sponge3};
use hgym_solvers::lbm::LbmError;

use super::{BoundaryKind, EdgeName, FlowError, FlowPlan, FlowSetup, GeometrySpec, Profile};

/// The 3D velocity set of a flow.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Lattice3Name {
    #[default]
    D3q19,
    D3q27,
}

impl Lattice3Name {
    /// Bytes of populations per node: Q f32 values in two copies.
    pub fn bytes_per_node(self) -> usize {
        match self {
            Lattice3Name::D3q19 => D3q19::BYTES_PER_CELL_F32,
            Lattice3Name::D3q27 => D3q27::BYTES_PER_CELL_F32,
        }
    }
}

/// The span of a 3D flow.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SpanSpec {
    /// `[z0, z1]` in reference lengths; `z1 - z0` must be a whole number of cells at every level.
    #[serde(deserialize_with = "super::pair")]
    pub z: [f64; 2],
    /// The two z faces: periodic (an infinite span), free-slip or wall.
    #[serde(default = "periodic")]
    pub boundary: BoundaryKind,
    /// Equal spanwise segments: forces (and the actuators of environments) per segment.
    #[serde(default = "one")]
    pub segments: usize,
    #[serde(default)]
    pub lattice: Lattice3Name,
}

fn periodic() -> BoundaryKind {
    BoundaryKind::Periodic
}

fn one() -> usize {
    1
}

impl SpanSpec {
    pub fn length(&self) -> f64 {
        self.z[1] - self.z[0]
    }

    /// Finite `z0 < z1`, a z boundary the span can have, at least one segment.
    pub(crate) fn check(&self) -> Result<(), FlowError> {
        let bad = |field, message: String| Err(FlowError::Invalid { field, message });
        if !(self.z.iter().all(|v| v.is_finite()) && self.z[0] < self.z[1]) {
            return bad("span.z", format!("must be a finite [z0, z1] with z0 < z1, got {:?}", self.z));
        }
        if matches!(self.boundary, BoundaryKind::Inlet | BoundaryKind::Outlet) {
            return bad(
                "span.boundary",
                format!("{:?} is not a spanwise face; use periodic, free-slip or wall", self.boundary),
            );
        }
        if self.segments == 0 {
            return bad("span.segments", "must be at least 1".into());
        }
        Ok(())
    }

    /// Nodes along z at `cells_per_length`; refused unless the span is a whole number of cells
    /// that the segments divide.
    pub(crate) fn nodes(&self, cells_per_length: f64, level: &str) -> Result<usize, FlowError> {
        let cells = self.length() * cells_per_length;
        let nz = cells.round();
        if (cells - nz).abs() > 1e-6 || nz < 1.0 {
            return Err(FlowError::Invalid {
                field: "span.z",
                message: format!(
                    "the span {} L is {cells:.3} cells at the {level} level ({cells_per_length} cells per L); it must be a \
                     whole number of cells: make it a multiple of {:.4} L",
                    self.length(),
                    1.0 / cells_per_length
                ),
            });
        }
        let nz = nz as usize;
        if !nz.is_multiple_of(self.segments) {
            return Err(FlowError::Invalid {
                field: "span.segments",
                message: format!(
                    "{} segments do not divide the {nz} cells of the span at the {level} level; use a divisor of {nz}",
                    self.segments
                ),
            });
        }
        Ok(nz)
    }
}

impl GeometrySpec {
    /// The body as a 3D solid: spheres and cubes as they are, 2D sections extruded along z.
    pub fn solid(&self) -> Box<dyn Solid> {
        match self {
            GeometrySpec::Sphere { center, diameter } => Box::new(Sphere {
                center: *center,
                radius: 0.5 * diameter,
            }),
            GeometrySpec::Cube { center, side } => Box::new(Cuboid {
                center: *center,
                size: [*side; 3],
            }),
            GeometrySpec::Pipe {
                center,
                diameter,
                length,
                severity,
            } => Box::new(StenosedPipe {
                center: *center,
                width: *diameter,
                length: *length,
                severity: *severity,
            }),
            other => Box::new(Extruded(other.shape())),
        }
    }
}

/// A 3D flow's solver, for either velocity set: one uniform box (split over the MPI ranks) or a
/// coarse box with nested 2:1 boxes around the bodies (whole on each rank).
pub enum LbmFlow3 {
    D3q19(Box<Lbm3<19, D3q19>>),
    D3q27(Box<Lbm3<27, D3q27>>),
    Refined19(Box<Refined3<19, D3q19>>),
    Refined27(Box<Refined3<27, D3q27>>),
}

/// Calls the same method on whichever uniform solver `self` holds, and `$refined` on a refined
/// one.
macro_rules! each {
    ($self:expr, $s:ident => $body:expr, $r:ident => $refined:expr) => {
        match $self {
            LbmFlow3::D3q19($s) => $body,
            LbmFlow3::D3q27($s) => $body,
            LbmFlow3::Refined19($r) => $refined,
            LbmFlow3::Refined27($r) => $refined,
        }
    };
}

/// Calls the same method on the box over the whole domain: the uniform solver, or a refined
/// flow's coarse grid (its faces, inlet and the fields outside the patches).
macro_rules! whole {
    ($self:expr, $s:ident => $body:expr) => {
        match $self {
            LbmFlow3::D3q19($s) => $body,
            LbmFlow3::D3q27($s) => $body,
            LbmFlow3::Refined19(r) => {
                let $s = r.coarse();
                $body
            }
            LbmFlow3::Refined27(r) => {
                let $s = r.coarse();
                $body
            }
        }
    };
    (mut $self:expr, $s:ident => $body:expr) => {
        match $self {
            LbmFlow3::D3q19($s) => $body,
            LbmFlow3::D3q27($s) => $body,
            LbmFlow3::Refined19(r) => {
                let $s = r.coarse_mut();
                $body
            }
            LbmFlow3::Refined27(r) => {
                let $s = r.coarse_mut();
                $body
            }
        }
    };
}

impl LbmFlow3 {
    pub fn step(&mut self) -> Result<(), LbmError> {
        each!(self, s => s.step(), r => r.step())
    }

    /// Whether the flow runs on nested boxes (environments run on one uniform box).
    pub fn is_refined(&self) -> bool {
        matches!(self, LbmFlow3::Refined19(_) | LbmFlow3::Refined27(_))
    }

    /// Force on each body in the level's lattice units (from the finest box when refined).
    pub fn body_forces(&self) -> &[[f64; 3]] {
        each!(self, s => s.body_forces(), r => r.body_forces())
    }

    /// Force on each (body, segment), `[b * segments + s]` (a refined flow has one segment).
    pub fn segment_forces(&self) -> &[[f64; 3]] {
        each!(self, s => s.segment_forces(), r => r.body_forces())
    }

    /// Shapes velocity face `face` by `profile(x)` at each node (see `Lbm3::set_face_profile`).
    pub fn set_face_profile(&mut self, face: usize, profile: impl Fn([f64; 3]) -> f64) -> Result<(), LbmError> {
        whole!(mut self, s => s.set_face_profile(face, profile))
    }

    /// The velocity of every node of the whole box (see `Lbm3::velocity_field`; a refined flow's
    /// coarse grid).
    pub fn velocity_field(&self, u: [&mut [f32]; 3]) -> Result<(), LbmError> {
        whole!(self, s => s.velocity_field(u))
    }

    /// Sets the velocity of a velocity face (`2 a` the low end of axis `a`), lattice units.
    pub fn set_face_velocity(&mut self, face: usize, u: [f64; 3]) -> Result<(), LbmError> {
        whole!(mut self, s => s.set_face_velocity(face, u))
    }

    pub fn set_boundary_velocity_scale(&mut self, scale: f64) {
        whole!(mut self, s => s.set_velocity_scale(scale))
    }

    /// Wall velocity of body `b` at each wall point (lattice velocities; every level).
    pub fn set_wall_velocity(&mut self, b: usize, u: impl Fn([f64; 3]) -> [f64; 3]) {
        each!(self, s => s.set_wall_velocity(b, u), r => r.set_wall_velocity(b, u))
    }

    /// Every fluid node at the equilibrium of `field(x, y, z) = (rho, u)` (physical positions,
    /// lattice velocities).
    pub fn init_with(&mut self, field: impl Fn([f64; 3]) -> (f64, [f64; 3])) {
        each!(self, s => {
            let grid = s.config().grid;
            s.set_equilibrium(|x, y, z| field(grid.position([x, y, z])))
        }, r => r.init_with(field))
    }

    /// Density and lattice velocity at a physical point (trilinear; from the finest box that
    /// holds it).
    pub fn probe(&self, x: [f64; 3]) -> Result<(f64, [f64; 3]), LbmError> {
        each!(self, s => s.probe(x), r => r.probe(x))
    }

    /// [`Self::probe`] at each point (one message over the ranks for all of them).
    pub fn probes(&self, xs: &[[f64; 3]]) -> Result<Vec<(f64, [f64; 3])>, LbmError> {
        each!(self, s => s.probes(xs), r => xs.iter().map(|&x| r.probe(x)).collect())
    }

    /// Gives a refined flow's coarse grid the fine solution under the patches (before reading
    /// its fields there); nothing for a uniform one.
    pub fn sync(&mut self) {
        each!(self, _s => (), r => r.sync())
    }

    pub fn time(&self) -> u64 {
        whole!(self, s => s.time())
    }

    /// Nodes of the box over the whole domain.
    pub fn n(&self) -> [usize; 3] {
        whole!(self, s => s.config().n)
    }

    pub fn grid(&self) -> Grid3 {
        whole!(self, s => s.config().grid)
    }

    /// Node updates per step (every level's, `2^l` times on level `l`), for MLUPS.
    pub fn node_updates_per_step(&self) -> usize {
        each!(self, s => s.config().n.iter().product(), r => r.node_updates_per_step())
    }

    /// Whether node `p` of the whole box is inside a body (a node this rank holds, under MPI).
    pub fn is_solid(&self, p: [usize; 3]) -> bool {
        whole!(self, s => s.is_solid(p))
    }

    /// Density and lattice velocity of node `p` of the whole box (a node this rank holds).
    pub fn rho_u(&self, p: [usize; 3]) -> (f64, [f64; 3]) {
        whole!(self, s => s.rho_u(p))
    }

    /// Lattice velocity of every node of plane `z` of the whole box, `[y nx + x]`, `None` inside
    /// bodies (every rank gets the whole plane; [`Self::sync`] first when refined).
    pub fn velocity_plane(&self, z: usize) -> Vec<Option<[f64; 3]>> {
        whole!(self, s => s.velocity_plane(z))
    }

    /// This process's rank and the number of ranks the box is split over (a refined flow runs
    /// whole on each).
    pub fn rank(&self) -> (usize, usize) {
        each!(self, s => s.rank(), _r => (0, 1))
    }

    /// Whether `yes` holds on every rank (every rank must ask together).
    pub fn all_ranks(&self, yes: bool) -> bool {
        each!(self, s => s.all_ranks(yes), _r => yes)
    }

    /// Mass body `b`'s moving walls inject per step (lattice units; see `Lbm3::wall_mass_source`;
    /// the coarse grid's when refined).
    pub fn wall_mass_source(&self, b: usize) -> f64 {
        whole!(self, s => s.wall_mass_source(b))
    }

    /// The populations (the state a developed-flow cache keeps) of the whole box.
    pub fn populations(&self) -> &[f32] {
        whole!(self, s => s.populations_raw())
    }

    /// Restores populations of a solver of the same set-up and level, and the step count.
    pub fn set_populations(&mut self, f: &[f32], time: u64) -> Result<(), LbmError> {
        each!(self, s => s.set_populations(f, time), _r => Err(LbmError::Config {
            field: "refinement",
            message: "a refined flow's state is not restored from one box's populations; remove the refinement".into(),
        }))
    }
}

impl FlowSetup {
    /// Builds the 3D solver at `plan` (a set-up with a span): faces from the boundaries and the
    /// span, the inlet's velocity (uniform, or a pipe's Poiseuille profile), collision, subgrid
    /// viscosity, absorbing layers on the x and y faces, the bodies as solids. The fluid starts
    /// at rest; callers set their initial state.
    pub fn build3(&self, plan: &FlowPlan) -> Result<LbmFlow3, FlowError> {
        let Some(span) = &self.span else {
            return Err(FlowError::Invalid {
                field: "span",
                message: "a 2D flow has no span; build it with `build`".into(),
            });
        };
        let u = self.lattice_velocity as f32;
        let face = |k: BoundaryKind| match k {
            BoundaryKind::Inlet => Face::Velocity([u, 0.0, 0.0]),
            BoundaryKind::Outlet => Face::Outlet,
            BoundaryKind::Periodic => Face::Periodic,
            BoundaryKind::Wall => Face::Wall,
            BoundaryKind::FreeSlip => Face::FreeSlip,
        };
        let b = &self.boundaries;
        let d = &self.domain;
        let nz = plan.nz.ok_or_else(|| FlowError::Invalid {
            field: "span",
            message: "the plan is a 2D one; make it from this set-up with `plan`".into(),
        })?;
        let mut cfg = D3Config::new([plan.nx, plan.ny, nz], plan.tau);
        cfg.faces = Faces([
            face(b.west),
            face(b.east),
            face(b.south),
            face(b.north),
            face(span.boundary),
            face(span.boundary),
        ]);
        cfg.grid = Grid3 {
            origin: [d.x[0] + 0.5 * plan.dx, d.y[0] + 0.5 * plan.dx, span.z[0] + 0.5 * plan.dx],
            dx: plan.dx,
        };
        cfg.segments = span.segments;
        cfg.collision = plan.collision;
        cfg.smagorinsky = self.smagorinsky;
        cfg.check_interval = super::build::CHECK_INTERVAL;
        cfg.sponges = self
            .sponges
            .iter()
            .map(|sp| {
                let layer = sp.lattice(plan.units.cells_per_length, self.lattice_velocity);
                Sponge3 {
                    face: match sp.edge {
                        EdgeName::West => 0,
                        EdgeName::East => 1,
                        EdgeName::South => 2,
                        EdgeName::North => 3,
                    },
                    width: layer.width,
                    strength: layer.strength,
                    rho: layer.rho,
                    u: [layer.u[0], layer.u[1], 0.0],
                }
            })
            .collect();
        let solids: Vec<Box<dyn Solid>> = self.bodies.iter().map(GeometrySpec::solid).collect();
        let bodies: Vec<&dyn Solid> = solids.iter().map(|b| b.as_ref()).collect();
        let built = match (span.lattice, &plan.refinement) {
            (Lattice3Name::D3q19, None) => {
                Lbm3::<19, D3q19>::new_split(cfg, &bodies, super::ranks::comm()).map(|s| LbmFlow3::D3q19(Box::new(s)))
            }
            (Lattice3Name::D3q27, None) => {
                Lbm3::<27, D3q27>::new_split(cfg, &bodies, super::ranks::comm()).map(|s| LbmFlow3::D3q27(Box::new(s)))
            }
            (Lattice3Name::D3q19, Some(r)) => Refined3::<19, D3q19>::new(cfg, &r.boxes, &bodies).map(|s| LbmFlow3::Refined19(Box::new(s))),
            (Lattice3Name::D3q27, Some(r)) => Refined3::<27, D3q27>::new(cfg, &r.boxes, &bodies).map(|s| LbmFlow3::Refined27(Box::new(s))),
        };
        let mut built = built.map_err(|e| match e {
            LbmError::Config { field, message } => FlowError::Invalid { field, message },
            other => FlowError::Solver(other),
        })?;
        // A parabolic 3D inlet is the laminar inflow of the duct it feeds (`check` makes sure
        // there is one).
        if self.inlet.profile == Profile::Parabolic {
            if let Some(duct) = self.bodies.iter().find(|b| b.is_duct()) {
                built
                    .set_face_profile(0, |p| duct.duct_inflow(p).unwrap_or(0.0))
                    .map_err(FlowError::Solver)?;
            }
        }
        Ok(built)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flow::Level;

    /// A sphere of diameter 1 in a 12 x 8 x 8 box: inlet, outlets on the other faces.
    fn sphere(extra: &str) -> String {
        format!(
            r#"
bodies = [{{ shape = "sphere", center = [4.0, 4.0, 4.0], diameter = 1.0 }}]
domain = {{ x = [0.0, 12.0], y = [0.0, 8.0] }}
boundaries = {{ west = "inlet", east = "outlet", south = "outlet", north = "outlet" }}
inlet = {{}}
reynolds = 100.0
lattice_velocity = 0.05
collision = "regularized"
smagorinsky = 0.0
resolution = {{ coarse = 4, default = 8, fine = 16 }}
sponges = []
{extra}
"#
        )
    }

    fn setup(text: &str) -> FlowSetup {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn a_span_gives_the_third_axis_and_the_3d_solver() {
        let s = setup(&sphere("span = { z = [0.0, 8.0], boundary = \"free-slip\", segments = 2 }"));
        s.check().unwrap();
        let plan = s.plan(Level::Coarse).unwrap();
        assert_eq!((plan.nx, plan.ny, plan.nz), (48, 32, Some(32)));
        assert_eq!(plan.bytes_per_node, 152);
        let mut flow = s.build3(&plan).unwrap();
        assert_eq!(flow.n(), [48, 32, 32]);
        // The node nearest the sphere's centre is solid, a corner is not.
        assert!(flow.is_solid([16, 16, 16]) && !flow.is_solid([0, 0, 0]));
        flow.init_with(|_| (1.0, [0.05, 0.0, 0.0]));
        for _ in 0..5 {
            flow.step().unwrap();
        }
        let drag = flow.body_forces()[0][0];
        let segments = flow.segment_forces();
        assert!(drag > 0.0, "{drag}");
        assert!((segments[0][0] + segments[1][0] - drag).abs() < 1e-12);
        assert!((s.reference_area() - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
        // The 2D builder refuses it.
        assert!(matches!(s.build(&plan), Err(FlowError::Invalid { field: "span", .. })));
    }

    #[test]
    fn refinement_boxes_take_the_nodes_covering_their_regions_and_build_the_refined_solver() {
        let span = "span = { z = [0.0, 8.0], boundary = \"free-slip\" }";
        let s = setup(&sphere(&format!(
            "{span}\nrefinement = {{ regions = [[2.5, 6.0, 2.75, 5.25, 3.0, 5.0]] }}"
        )));
        s.check().unwrap();
        let plan = s.plan(Level::Coarse).unwrap();
        let r = plan.refinement.as_ref().unwrap();
        // Coarse nodes at (i + 1/2) / 4: x 2.5 lies between nodes 9 and 10, 6.0 between 23 and 24.
        assert_eq!(r.boxes.len(), 1);
        assert_eq!((r.boxes[0].lo, r.boxes[0].hi), ([9, 10, 11], [24, 21, 20]));
        assert_eq!((r.cells_per_length, r.fine_nodes), (8.0, 31 * 23 * 19));
        assert!((r.tau - (0.5 + 2.0 * (plan.tau - 0.5))).abs() < 1e-12);
        let mut flow = s.build3(&plan).unwrap();
        assert!(flow.is_refined());
        assert_eq!(flow.node_updates_per_step(), 48 * 32 * 32 + 2 * 31 * 23 * 19);
        flow.init_with(|_| (1.0, [0.05, 0.0, 0.0]));
        for _ in 0..5 {
            flow.step().unwrap();
        }
        assert!(flow.body_forces()[0][0] > 0.0);
        // A probe inside the box reads the fine grid, one outside the coarse: both the free stream
        // far upstream.
        let (_, u) = flow.probe([0.5, 4.0, 4.0]).unwrap();
        assert!((u[0] - 0.05).abs() < 1e-3, "{u:?}");

        let field = |regions: &str| match setup(&sphere(&format!("{span}\nrefinement = {{ regions = {regions} }}"))).check() {
            Err(FlowError::Invalid { field, message }) => format!("{field}: {message}"),
            other => format!("{other:?}"),
        };
        let flat = field("[[2.5, 6.0, 2.75, 5.25]]");
        assert!(
            flat.starts_with("refinement.regions: region 1 must be [x0, x1, y0, y1, z0, z1]"),
            "{flat}"
        );
        let outside = field("[[2.5, 6.0, 2.75, 5.25, 3.0, 8.0]]");
        assert!(outside.contains("must lie inside the domain"), "{outside}");
    }

    #[test]
    fn a_box_may_cover_a_periodic_span_whole_and_its_grid_wraps_there() {
        let cylinder = |span: &str, regions: &str| {
            let text = sphere(&format!("{span}\nrefinement = {{ regions = {regions} }}"));
            setup(&text.replace(
                r#"shape = "sphere", center = [4.0, 4.0, 4.0]"#,
                r#"shape = "circle", center = [4.0, 4.0]"#,
            ))
        };
        let periodic = "span = { z = [0.0, 2.0] }";
        // Two boxes over the whole span (written as the span's ends or beyond them).
        let s = cylinder(periodic, "[[2.5, 6.0, 2.75, 5.25, 0.0, 2.0], [3.0, 5.5, 3.0, 5.0, -1.0, 3.0]]");
        s.check().unwrap();
        let plan = s.plan(Level::Coarse).unwrap();
        let r = plan.refinement.as_ref().unwrap();
        assert_eq!(plan.nz, Some(8));
        assert_eq!(r.boxes[0].lo[2], 0);
        assert_eq!(r.boxes[0].hi[2], 7);
        assert_eq!((r.boxes[1].lo[2], r.boxes[1].hi[2]), (0, 15));
        let [b0, b1] = [r.boxes[0], r.boxes[1]];
        let n1 = [2 * (b0.hi[0] - b0.lo[0]) + 1, 2 * (b0.hi[1] - b0.lo[1]) + 1, 16];
        let n2 = [2 * (b1.hi[0] - b1.lo[0]) + 1, 2 * (b1.hi[1] - b1.lo[1]) + 1, 32];
        assert_eq!(r.fine_nodes, n1.iter().product::<usize>() + n2.iter().product::<usize>());
        let mut flow = s.build3(&plan).unwrap();
        assert_eq!(
            flow.node_updates_per_step(),
            48 * 32 * 8 + 2 * n1.iter().product::<usize>() + 4 * n2.iter().product::<usize>()
        );
        flow.init_with(|_| (1.0, [0.05, 0.0, 0.0]));
        for _ in 0..3 {
            flow.step().unwrap();
        }
        assert!(flow.body_forces()[0][0] > 0.0);

        // Only a periodic span can be covered.
        let walls = cylinder(
            "span = { z = [0.0, 2.0], boundary = \"free-slip\" }",
            "[[2.5, 6.0, 2.75, 5.25, 0.0, 2.0]]",
        );
        match walls.check() {
            Err(FlowError::Invalid { field, message }) => {
                assert_eq!(field, "refinement.regions");
                assert!(message.contains("must lie inside the domain"), "{message}");
                assert!(!message.contains("cover the periodic span"), "{message}");
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn refuses_what_a_span_cannot_hold() {
        let field = |extra: &str| match setup(&sphere(extra))
            .check()
            .and_then(|_| setup(&sphere(extra)).plan(Level::Fine).map(|_| ()))
        {
            Err(FlowError::Invalid { field, message }) => format!("{field}: {message}"),
            other => format!("{other:?}"),
        };
        assert!(field("").starts_with("bodies: a sphere needs a 3D flow"), "{}", field(""));
        // 8.1 L is 32.4 cells at the coarse level.
        assert!(
            field("span = { z = [0.0, 8.1] }").starts_with("span.z:"),
            "{}",
            field("span = { z = [0.0, 8.1] }")
        );
        assert!(field("span = { z = [0.0, 8.0], segments = 3 }").starts_with("span.segments:"));
        // A sphere that crosses the periodic z faces.
        assert!(field("span = { z = [3.25, 7.25] }").starts_with("bodies: body 1 spans z"));
        assert!(field("span = { z = [0.0, 8.0], boundary = \"inlet\" }").starts_with("span.boundary:"));
    }
}
