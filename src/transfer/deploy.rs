//! Zero-shot deployment (a protocol's `[deployment]` table; the channel -> wing): a policy acts on
//! the target with no training there, beside the uncontrolled flow and classical controllers
//! deployed the same way. Each deployment runs the protocol's evaluation episodes and measures,
//! over the actions after the first `settle_actions` (the controlled layer's transient, while it
//! convects over the region):
//! - the local skin-friction reduction over the control region,
//!   `100 (1 - <tau_w> / <tau_w,0>)` (info `tau_w`, the region's mean), against the uncontrolled
//!   flow from the same state;
//! - the reduction of the plate's friction drag, `100 (1 - <C_D> / <C_D,0>)` (info `C_D`);
//! - the actuation in local wall units (info `actuation_rms_plus`, `actuation_mean_plus`);
//! - the time mean of the environment's wall field (the wing's `tau_w / tau_w,0(x) - 1`) and its
//!   spanwise mean along `x`.

use hgym_agents::policy::Policy;
use hgym_agents::{EnvError, StepResult};
use serde::{Deserialize, Serialize};

use crate::env::FlowEnv;
use crate::report::eval::{nan_if_null, EvalEpisode, Stat};
use crate::train::eval::{eval_episode, Uncontrolled};

/// What one deployment episode measured over its actions after the transient.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeployEpisode {
    pub seed: u64,
    /// Mean wall shear stress over the control region.
    #[serde(deserialize_with = "nan_if_null")]
    pub tau_w: f64,
    /// Mean friction drag coefficient of the plate.
    #[serde(deserialize_with = "nan_if_null")]
    pub c_d: f64,
    /// The plate's mean C_D over the whole episode (the evaluation report's figure).
    #[serde(deserialize_with = "nan_if_null")]
    pub c_d_episode: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub actuation_rms_plus: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub actuation_mean_plus: f64,
    /// Against the uncontrolled episode from the same state (0 for the uncontrolled flow).
    #[serde(deserialize_with = "nan_if_null")]
    pub local_friction_reduction_pct: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub plate_drag_reduction_pct: f64,
}

/// The time mean of a wall field over the deployment's measured actions.
#[derive(Clone, Debug, PartialEq)]
pub struct MeanField {
    pub name: String,
    pub nx: usize,
    pub ny: usize,
    pub extent: [f64; 4],
    pub values: Vec<f32>,
}

impl MeanField {
    /// `x` of each column and the field's mean over each column (the spanwise mean).
    pub fn profile(&self) -> (Vec<f64>, Vec<f64>) {
        let dx = (self.extent[1] - self.extent[0]) / self.nx as f64;
        let x = (0..self.nx).map(|i| self.extent[0] + (i as f64 + 0.5) * dx).collect();
        let mean = (0..self.nx)
            .map(|i| (0..self.ny).map(|j| self.values[j * self.nx + i] as f64).sum::<f64>() / self.ny as f64)
            .collect();
        (x, mean)
    }
}

/// One deployment: per episode the evaluation report's figures and the deployment's own, and
/// the mean wall field (`None` when the environment has no field).
pub struct Deployment {
    pub eval: Vec<EvalEpisode>,
    pub episodes: Vec<DeployEpisode>,
    pub field: Option<MeanField>,
}

impl Deployment {
    pub fn local_friction_reduction_pct(&self) -> Stat {
        Stat::of(&self.episodes.iter().map(|e| e.local_friction_reduction_pct).collect::<Vec<_>>())
    }

    pub fn plate_drag_reduction_pct(&self) -> Stat {
        Stat::of(&self.episodes.iter().map(|e| e.plate_drag_reduction_pct).collect::<Vec<_>>())
    }

    /// The record of this deployment as `arm` (ids: policy, env ID, spec hash, level).
    pub fn record(&self, arm: &str, seed: Option<u64>, ids: [&str; 4], settle: usize, cpu_s: f64) -> ArmRecord {
        let (x, profile) = self.field.as_ref().map(MeanField::profile).unwrap_or_default();
        ArmRecord {
            schema: ArmRecord::SCHEMA.into(),
            arm: arm.into(),
            seed,
            policy: ids[0].into(),
            policy_sha256: None,
            env_id: ids[1].into(),
            spec_hash: ids[2].into(),
            level: ids[3].into(),
            settle_actions: settle,
            local_friction_reduction_pct: self.local_friction_reduction_pct(),
            plate_drag_reduction_pct: self.plate_drag_reduction_pct(),
            actuation_rms_plus: Stat::of(&self.episodes.iter().map(|e| e.actuation_rms_plus).collect::<Vec<_>>()),
            episodes: self.episodes.clone(),
            cpu_s_per_episode: cpu_s / self.episodes.len().max(1) as f64,
            field: self.field.as_ref().map(|f| f.name.clone()).unwrap_or_default(),
            x,
            profile,
        }
    }
}

/// One arm's deployment as written to `<arm>/deployment.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArmRecord {
    pub schema: String,
    /// `uncontrolled`, `zeroshot` or a baseline's name.
    pub arm: String,
    /// The source seed of a zero-shot arm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    pub policy: String,
    /// A zero-shot arm's: SHA-256 of the source's `policy.json` it deployed (a source retrained
    /// in the same folder is then told apart).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub policy_sha256: Option<String>,
    pub env_id: String,
    pub spec_hash: String,
    pub level: String,
    pub settle_actions: usize,
    pub episodes: Vec<DeployEpisode>,
    pub local_friction_reduction_pct: Stat,
    pub plate_drag_reduction_pct: Stat,
    pub actuation_rms_plus: Stat,
    /// CPU time of one episode (the deployment's, divided by its episodes).
    pub cpu_s_per_episode: f64,
    /// The wall field's name and its time and spanwise mean at each `x`.
    pub field: String,
    pub x: Vec<f64>,
    pub profile: Vec<f64>,
}

impl ArmRecord {
    pub const SCHEMA: &'static str = "hgym/deployment-arm/v1";
}

/// Sums of the measured figures over an episode's actions after the transient.
#[derive(Default)]
struct Window {
    n: usize,
    tau_w: f64,
    c_d: f64,
    rms: f64,
    mean: f64,
}

impl Window {
    fn add(&mut self, r: &StepResult) {
        let get = |k: &str| r.info.get(k).unwrap_or(f64::NAN);
        self.n += 1;
        self.tau_w += get("tau_w");
        self.c_d += get("C_D");
        self.rms += get("actuation_rms_plus");
        self.mean += get("actuation_mean_plus");
    }
}

/// Runs `policy` for one episode per seed, measuring after `settle` actions; `reference` is the
/// uncontrolled deployment's episodes on the same seeds (`None`: this is the uncontrolled one).
/// `progress` gets the actions taken so far.
pub fn deploy(
    env: &mut dyn FlowEnv,
    policy: &mut dyn Policy,
    seeds: &[u64],
    settle: usize,
    reference: Option<&[DeployEpisode]>,
    progress: &mut dyn FnMut(usize),
) -> Result<Deployment, EnvError> {
    let mut out = Deployment {
        eval: vec![],
        episodes: vec![],
        field: None,
    };
    let (mut frames, mut done) = (0usize, 0usize);
    for (k, &seed) in seeds.iter().enumerate() {
        let baseline = reference.and_then(|r| r.get(k));
        let c_d0 = Uncontrolled::drag(baseline.map_or(f64::NAN, |b| b.c_d_episode));
        let mut w = Window::default();
        let mut step = 0;
        let field = &mut out.field;
        let (mut eval, stats) = eval_episode(env, policy, seed, &c_d0, None, &mut |env, r| {
            step += 1;
            done += 1;
            progress(done);
            if step <= settle {
                return;
            }
            w.add(r);
            let snap = env.snapshot();
            if let Some((name, values)) = snap.fields.first() {
                let f = field.get_or_insert_with(|| MeanField {
                    name: name.clone(),
                    nx: snap.nx,
                    ny: snap.ny,
                    extent: snap.extent,
                    values: vec![0.0; values.len()],
                });
                f.values.iter_mut().zip(values).for_each(|(m, v)| *m += v);
                frames += 1;
            }
        })?;
        let n = w.n.max(1) as f64;
        let (tau_w, c_d) = (w.tau_w / n, w.c_d / n);
        let (tau0, c_d_0) = baseline.map_or((tau_w, c_d), |b| (b.tau_w, b.c_d));
        if baseline.is_none() {
            eval.uncontrolled_c_d = eval.mean_c_d;
            eval.drag_reduction_pct = 0.0;
        }
        out.episodes.push(DeployEpisode {
            seed,
            tau_w,
            c_d,
            c_d_episode: stats.info_means.get("C_D").copied().unwrap_or(f64::NAN),
            actuation_rms_plus: w.rms / n,
            actuation_mean_plus: w.mean / n,
            local_friction_reduction_pct: 100.0 * (1.0 - tau_w / tau0),
            plate_drag_reduction_pct: 100.0 * (1.0 - c_d / c_d_0),
        });
        out.eval.push(eval);
    }
    if let Some(f) = &mut out.field {
        let n = frames.max(1) as f32;
        f.values.iter_mut().for_each(|v| *v /= n);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use hgym_agents::baselines::{Baseline, BaselinePolicy};

    fn tiny_wing() -> Box<dyn FlowEnv> {
        let spec = crate::env::lookup("WingTBL_3D_Rec200000").unwrap();
        let over: toml::Table = toml::from_str(
            "grid = { coarse = [96, 32, 8], default = [96, 32, 8], fine = [96, 32, 8] }\n\
             patch_cells = { coarse = [6, 2], default = [6, 2], fine = [6, 2] }\n\
             spin_up = 0.002\nstretch = 3.2\nepisode_actions = 6\nzero_net_flux = false",
        )
        .unwrap();
        spec.with_overrides(&over).unwrap().make(crate::flow::Level::Coarse, None).unwrap()
    }

    /// The uncontrolled flow measured against itself reduces nothing; a controller measured against
    /// it reports the reductions of its own means, over the actions after the transient only.
    #[test]
    fn reductions_are_against_the_uncontrolled_flow_after_the_transient() {
        let mut env = tiny_wing();
        let seeds = [0, 1];
        let mut zero = BaselinePolicy::new(Baseline::Zero, 0);
        let u = deploy(env.as_mut(), &mut zero, &seeds, 2, None, &mut |_| {}).unwrap();
        assert_eq!(u.local_friction_reduction_pct().mean, 0.0);
        assert_eq!(u.eval[0].drag_reduction_pct, 0.0);
        let f = u.field.as_ref().unwrap();
        assert_eq!(f.values.len(), f.nx * f.ny);
        let mut blow = BaselinePolicy::new(Baseline::Constant { values: vec![0.5] }, 0);
        let mut again = tiny_wing();
        let b = deploy(again.as_mut(), &mut blow, &seeds, 2, Some(&u.episodes), &mut |_| {}).unwrap();
        for (e, e0) in b.episodes.iter().zip(&u.episodes) {
            assert_eq!(e.local_friction_reduction_pct, 100.0 * (1.0 - e.tau_w / e0.tau_w));
            assert!(e.tau_w.is_finite() && e.tau_w != e0.tau_w);
        }
        // The same uncontrolled flow from the same seeds, measured again, gives the same figures.
        let mut third = tiny_wing();
        let u2 = deploy(third.as_mut(), &mut zero, &seeds, 2, None, &mut |_| {}).unwrap();
        assert_eq!(u.episodes, u2.episodes);
    }
}
