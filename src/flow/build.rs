//! The one function that makes a lattice-Boltzmann solver from a flow set-up
//! ([`FlowSetup::build`]), used by validation cases and environments alike, and the solver it
//! makes: one uniform grid, or a coarse grid with nested 2:1 patches ([`LbmFlow`]).

use hgym_solvers::lbm::{D2q9, D2q9Config, Grid, LbmError, Refined};

use super::{FlowError, FlowPlan, FlowSetup};

/// Steps between the solver's full scans for NaN, density and speed bounds.
pub const CHECK_INTERVAL: u64 = 100;

impl FlowSetup {
    /// The lattice speed of the inflow at height `y` (the initial state's velocity).
    pub fn inlet_velocity(&self, y: f64) -> f64 {
        let d = &self.domain;
        self.lattice_velocity * self.inlet.shape((y - d.y[0]) / (d.y[1] - d.y[0]))
    }

    /// The solver's grid: cell-centred nodes of spacing `plan.dx` from the domain's corner.
    pub fn grid(&self, plan: &FlowPlan) -> Grid {
        let d = &self.domain;
        Grid {
            origin: [d.x[0] + 0.5 * plan.dx, d.y[0] + 0.5 * plan.dx],
            dx: plan.dx,
        }
    }

    /// Builds the solver at `plan` (from [`FlowSetup::plan`]): edges, inlet profile (its value at
    /// each row's centre `eta = (j + 1/2) / ny`), collision, subgrid viscosity, absorbing layers,
    /// the characteristic inlet, the bodies, and the refined patches if the plan has them. The
    /// fluid is left at rest with unit density; callers set their initial state. Under MPI a
    /// uniform grid is split over the ranks ([`super::ranks`]); a refined one runs whole on each.
    pub fn build(&self, plan: &FlowPlan) -> Result<LbmFlow, FlowError> {
        if self.span.is_some() {
            return Err(FlowError::Invalid {
                field: "span",
                message: "a 3D flow (it has a span); build it with `build3`".into(),
            });
        }
        let n = plan.units.cells_per_length;
        let u = self.lattice_velocity;
        let ny = plan.ny;
        let inlet: Vec<[f32; 2]> = (0..ny)
            .map(|j| [self.inlet.shape((j as f64 + 0.5) / ny as f64) as f32 * u as f32, 0.0])
            .collect();
        let mut cfg = D2q9Config::new(plan.nx, ny, plan.tau, self.boundaries.sides(&inlet));
        cfg.collision = plan.collision;
        cfg.smagorinsky = self.smagorinsky;
        cfg.grid = self.grid(plan);
        cfg.check_interval = CHECK_INTERVAL;
        cfg.sponges = self.sponges.iter().map(|sp| sp.lattice(n, u)).collect();
        if self.inlet.characteristic_time > 0.0 {
            cfg.characteristic_inlet = Some(self.inlet.characteristic_time * n / u);
        }
        let bodies = self.bodies.iter().map(|b| b.shape()).collect();
        let built = match &plan.refinement {
            None => D2q9::new_split(cfg, bodies, super::ranks::comm()).map(|s| LbmFlow::Uniform(Box::new(s))),
            Some(r) => Refined::new(cfg, &r.patches, bodies).map(LbmFlow::Refined),
        };
        built.map_err(|e| match e {
            LbmError::Config { field, message } => FlowError::Invalid { field, message },
            other => FlowError::Solver(other),
        })
    }
}

/// The grid(s) a flow runs on: one uniform grid, or a coarse grid with nested 2:1 patches.
pub enum LbmFlow {
    Uniform(Box<D2q9>),
    Refined(Refined),
}

impl LbmFlow {
    pub fn step(&mut self) -> Result<(), LbmError> {
        match self {
            LbmFlow::Uniform(s) => s.step(),
            LbmFlow::Refined(r) => r.step(),
        }
    }

    /// Forces on the bodies in the level's lattice units (from the finest patch when refined).
    pub fn body_forces(&self) -> &[[f64; 2]] {
        match self {
            LbmFlow::Uniform(s) => s.body_forces(),
            LbmFlow::Refined(r) => r.body_forces(),
        }
    }

    pub fn set_boundary_velocity_scale(&mut self, scale: f64) {
        match self {
            LbmFlow::Uniform(s) => s.set_boundary_velocity_scale(scale),
            LbmFlow::Refined(r) => r.set_boundary_velocity_scale(scale),
        }
    }

    /// Sets every node to the equilibrium of `field(x, y) = (rho, u, v)` (lattice units).
    pub fn init_with(&mut self, field: impl FnMut(f64, f64) -> (f64, f64, f64)) {
        match self {
            LbmFlow::Uniform(s) => s.init_with(field),
            LbmFlow::Refined(r) => r.init_with(field),
        }
    }

    /// Gives the coarse grid the fine solution under the patches (see `Refined::sync`).
    pub fn sync(&mut self) {
        if let LbmFlow::Refined(r) = self {
            r.sync();
        }
    }

    /// The grid over the whole domain (call `sync` first to read it under the patches).
    pub fn coarse(&self) -> &D2q9 {
        match self {
            LbmFlow::Uniform(s) => s,
            LbmFlow::Refined(r) => r.coarse(),
        }
    }

    pub fn time(&self) -> u64 {
        self.coarse().time()
    }

    pub fn node_updates_per_step(&self) -> usize {
        match self {
            LbmFlow::Uniform(s) => s.fluid_nodes(),
            LbmFlow::Refined(r) => r.node_updates_per_step(),
        }
    }

    /// The uniform grid, or an error for a refined flow (environments run on one grid).
    pub fn into_uniform(self) -> Result<D2q9, FlowError> {
        match self {
            LbmFlow::Uniform(s) => Ok(*s),
            LbmFlow::Refined(_) => Err(FlowError::Invalid {
                field: "refinement",
                message: "environments run on one uniform grid; remove the refinement regions".into(),
            }),
        }
    }
}
