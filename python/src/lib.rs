//! `hgym._hgym`: hgym's flow environments behind PyO3, for the Gymnasium classes in
//! `python/hgym/`. The Rust environment is the one `hgym train` and `hgym eval` run (same
//! registry, specs, overrides and seeds), so an observation through Python is bitwise the
//! Rust one (converted to float32 for Gymnasium's `Box`). The GIL is released while a solver
//! steps; a vector environment steps its instances on Rust threads (rayon) in one call.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use hgym::env::{FlowEnv, Spec};
use hgym::flow::Level;
use hgym_agents::{EnvError, Info};
use numpy::ndarray::{Dimension, IntoDimension};
use numpy::{PyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use rayon::prelude::*;

/// A user's mistake (unknown ID, bad override, bad action) is a `ValueError`; a failure of the
/// run itself a `RuntimeError`. Messages are the Rust ones, word for word.
fn env_error(e: EnvError) -> PyErr {
    match e {
        EnvError::Backend(m) => PyRuntimeError::new_err(m),
        EnvError::NeedsReset => PyRuntimeError::new_err(e.to_string()),
        e => PyValueError::new_err(e.to_string()),
    }
}

fn level(name: &str) -> PyResult<Level> {
    name.parse()
        .map_err(|e: hgym::flow::UnknownLevel| PyValueError::new_err(e.to_string()))
}

/// The spec of `id` with `overrides` (a JSON object of spec fields, as `[env]` in a train
/// config) merged in and checked.
fn spec(id: &str, overrides: Option<&str>) -> PyResult<Spec> {
    let spec = hgym::env::lookup(id).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let Some(json) = overrides else { return Ok(spec) };
    let table: toml::Table = serde_json::from_str(json).map_err(|e| {
        PyValueError::new_err(format!(
            "overrides of {id}: {e} (keyword values must be numbers, strings, booleans, lists or dicts; not None)"
        ))
    })?;
    if table.is_empty() {
        return Ok(spec);
    }
    spec.with_overrides(&table).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// `f` with the GIL released, inside this thread's own rayon pool, of which the calling thread
/// is worker 0 (`use_current_thread`) and which has as many threads as rayon's global pool
/// (`RAYON_NUM_THREADS`): `f` runs right here, with no hand-over to another thread and back
/// (two thread wake-ups, tens of microseconds, which a small flow's whole step can cost), and a
/// solver's parallel loops inside `f` start within the pool as they do under `hgym train`.
fn detached<R: Send>(py: Python<'_>, f: impl FnOnce() -> R + Send) -> PyResult<R> {
    thread_local! {
        static POOL: std::cell::OnceCell<Result<rayon::ThreadPool, String>> = const { std::cell::OnceCell::new() };
    }
    py.detach(|| {
        POOL.with(|pool| {
            let pool = pool.get_or_init(|| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(rayon::current_num_threads())
                    .use_current_thread()
                    .build()
                    .map_err(|e| format!("cannot start hgym's worker threads: {e}"))
            });
            match pool {
                Ok(pool) => Ok(pool.install(f)),
                Err(e) => Err(PyRuntimeError::new_err(e.clone())),
            }
        })
    })
}

fn make(spec: &Spec, level: Level) -> PyResult<Box<dyn FlowEnv>> {
    spec.make(level, hgym::env::default_cache_dir()).map_err(env_error)
}

/// The info keys as Python strings, made once: an environment reports the same keys every
/// step, and a new string per key and step (allocated, checked, hashed) is most of what building
/// the info dict costs.
#[derive(Default)]
struct InfoKeys(Mutex<Vec<(String, Py<PyString>)>>);

impl InfoKeys {
    /// `info` as a Python dict (numbers as float, texts as str).
    fn dict<'py>(&self, py: Python<'py>, info: &Info) -> PyResult<Bound<'py, PyDict>> {
        let mut keys = self
            .0
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the info keys were poisoned by an earlier failure"))?;
        let d = PyDict::new(py);
        let mut i = 0;
        for (k, v) in &info.values {
            d.set_item(Self::key(&mut keys, py, i, k), *v)?;
            i += 1;
        }
        for (k, v) in &info.text {
            d.set_item(Self::key(&mut keys, py, i, k), v)?;
            i += 1;
        }
        Ok(d)
    }

    /// The `i`-th key, `name`: the string kept from an earlier call if it is the same.
    fn key<'py>(keys: &mut Vec<(String, Py<PyString>)>, py: Python<'py>, i: usize, name: &str) -> Bound<'py, PyString> {
        match keys.get(i) {
            Some((kept, k)) if kept == name => k.bind(py).clone(),
            _ => {
                let k = PyString::new(py, name);
                keys.truncate(i);
                keys.push((name.to_string(), k.clone().unbind()));
                k
            }
        }
    }
}

/// An observation (float32), `(low, high)` of a space, and the infos of a vector step.
type Obs<'py> = Bound<'py, PyArray1<f32>>;
type Bounds<'py> = (Obs<'py>, Obs<'py>);
type Infos<'py> = Vec<Bound<'py, PyDict>>;

/// A float32 array of shape `dims` that numpy allocates, written in place from `values`
/// (narrowed from f64): no buffer in between, and no Python object of its own to keep a Rust
/// `Vec` alive as an array made from one would need.
fn f32_array<'py, D: Dimension>(
    py: Python<'py>,
    dims: impl IntoDimension<Dim = D>,
    values: impl Iterator<Item = f64>,
) -> PyResult<Bound<'py, PyArray<f32, D>>> {
    let a = PyArray::<f32, D>::zeros(py, dims, false);
    for (slot, v) in a.try_readwrite()?.as_slice_mut()?.iter_mut().zip(values) {
        *slot = v as f32;
    }
    Ok(a)
}

fn obs_array<'py>(py: Python<'py>, obs: &[f64]) -> PyResult<Obs<'py>> {
    f32_array(py, obs.len(), obs.iter().copied())
}

fn bounds<'py>(py: Python<'py>, space: &hgym_agents::BoxSpace) -> PyResult<Bounds<'py>> {
    Ok((obs_array(py, &space.low)?, obs_array(py, &space.high)?))
}

/// One environment. The Python class `hgym.HgymEnv` wraps it with Gymnasium's API.
#[pyclass(module = "hgym._hgym")]
struct Env {
    env: Mutex<Box<dyn FlowEnv>>,
    spec: Spec,
    level: Level,
    /// Nanoseconds spent inside `FlowEnv::step` over every `step` call, so that the boundary's
    /// own cost (the rest of the call) can be measured on the same calls.
    step_ns: AtomicU64,
    keys: InfoKeys,
}

impl Env {
    fn env(&self) -> PyResult<std::sync::MutexGuard<'_, Box<dyn FlowEnv>>> {
        self.env
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the environment failed in an earlier call; make a new one"))
    }
}

#[pymethods]
impl Env {
    /// `Env(id, level="coarse", overrides=None)`: `overrides` is a JSON object of spec fields.
    #[new]
    #[pyo3(signature = (id, level = "coarse", overrides = None))]
    fn new(id: &str, level: &str, overrides: Option<&str>) -> PyResult<Self> {
        let lvl = self::level(level)?;
        let spec = spec(id, overrides)?;
        let env = make(&spec, lvl)?;
        Ok(Env {
            env: Mutex::new(env),
            spec,
            level: lvl,
            step_ns: AtomicU64::new(0),
            keys: InfoKeys::default(),
        })
    }

    #[getter]
    fn id(&self) -> String {
        self.spec.id().to_string()
    }

    #[getter]
    fn level(&self) -> &'static str {
        self.level.name()
    }

    /// The spec as TOML (what `hgym envs show ID` prints, overrides applied).
    #[getter]
    fn spec_toml(&self) -> String {
        self.spec.to_toml()
    }

    /// Seconds spent inside the Rust environment's `step` over all `step` calls so far (what a
    /// call costs beyond it is the Python boundary; `hgym bench python` reads it).
    #[getter]
    fn step_seconds(&self) -> f64 {
        self.step_ns.load(Ordering::Relaxed) as f64 * 1e-9
    }

    #[getter]
    fn spec_hash(&self) -> String {
        self.spec.hash()
    }

    #[getter]
    fn control_interval(&self) -> f64 {
        self.spec.control_interval()
    }

    #[getter]
    fn differentiable(&self) -> bool {
        self.spec.differentiable()
    }

    /// `(low, high)` of the observation space, float32.
    fn observation_bounds<'py>(&self, py: Python<'py>) -> PyResult<Bounds<'py>> {
        bounds(py, &self.env()?.observation_space())
    }

    /// `(low, high)` of the action space, float32.
    fn action_bounds<'py>(&self, py: Python<'py>) -> PyResult<Bounds<'py>> {
        bounds(py, &self.env()?.action_space())
    }

    /// `reset(seed) -> (obs, info)`; the first reset of a flow spins it up (cached on disk).
    fn reset<'py>(&self, py: Python<'py>, seed: u64) -> PyResult<(Obs<'py>, Bound<'py, PyDict>)> {
        let mut guard = self.env()?;
        let env: &mut dyn FlowEnv = &mut **guard;
        let (obs, info) = detached(py, || env.reset(seed))?.map_err(env_error)?;
        Ok((obs_array(py, &obs)?, self.keys.dict(py, &info)?))
    }

    /// `step(action) -> (obs, reward, terminated, truncated, info)`; `action` a contiguous 1-D
    /// numpy array of float64, or of float32 (what Gymnasium's `Box` samples; widened exactly).
    /// Anything else is a `TypeError`, which `HgymEnv.step` answers by converting.
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &self,
        py: Python<'py>,
        action: &Bound<'py, PyAny>,
    ) -> PyResult<(Bound<'py, PyArray1<f32>>, f64, bool, bool, Bound<'py, PyDict>)> {
        let not_flat = |e: numpy::AsSliceError| PyTypeError::new_err(format!("the action: {e}"));
        // Copied under the GIL (a few numbers): no borrow of the array outlives this line, so
        // none needs registering with numpy's borrow checker while the solver steps.
        let action: Vec<f64> = if let Ok(a) = action.cast::<PyArray1<f64>>() {
            a.to_vec().map_err(not_flat)?
        } else if let Ok(a) = action.cast::<PyArray1<f32>>() {
            a.to_vec().map_err(not_flat)?.into_iter().map(f64::from).collect()
        } else {
            return Err(PyTypeError::new_err("the action must be a 1-D numpy array of float32 or float64"));
        };
        let mut guard = self.env()?;
        let env: &mut dyn FlowEnv = &mut **guard;
        let (r, ns) = detached(py, || {
            let t = Instant::now();
            let r = env.step(&action);
            (r, t.elapsed().as_nanos() as u64)
        })?;
        self.step_ns.fetch_add(ns, Ordering::Relaxed);
        let r = r.map_err(env_error)?;
        Ok((
            obs_array(py, &r.obs)?,
            r.reward,
            r.terminated,
            r.truncated,
            self.keys.dict(py, &r.info)?,
        ))
    }

    /// The vorticity (for a flow without one, its first snapshot field: the channels' wall shear
    /// stress excess) as an RGB image (rows from the top of the domain), colour range `+-vmax`
    /// (default: the 98th percentile of |field|); bodies grey.
    #[pyo3(signature = (vmax = None))]
    fn render_rgb<'py>(&self, py: Python<'py>, vmax: Option<f64>) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let snap = self.env()?.snapshot();
        let w = snap
            .fields
            .iter()
            .find(|(name, _)| name == "vorticity")
            .or(snap.fields.first())
            .map(|(_, v)| v)
            .ok_or_else(|| PyRuntimeError::new_err("this environment has no flow field to show"))?;
        let vmax = vmax.unwrap_or_else(|| hgym::report::plots::abs_quantile(w, 0.98));
        let rgb = hgym::report::plots::field_rgb(snap.nx, snap.ny, w, vmax);
        PyArray1::from_vec(py, rgb)
            .reshape([snap.ny, snap.nx, 3])
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// How the flow splits into agents (`hgym_agents::multi`), or `None`: a dict with `obs` and
    /// `act` (per agent, the global indices of its observation and of its actions) and `reward`
    /// (`"global"` or `"local"`).
    fn agents<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(a) = self.env()?.agents() else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("obs", a.obs)?;
        d.set_item("act", a.act)?;
        d.set_item(
            "reward",
            match a.reward {
                hgym_agents::multi::AgentReward::Global => "global",
                hgym_agents::multi::AgentReward::Local => "local",
            },
        )?;
        Ok(Some(d))
    }

    /// The last step's reward of each agent (local rewards).
    fn agent_rewards(&self) -> PyResult<Vec<f64>> {
        Ok(self.env()?.agent_rewards())
    }

    /// For the last `k` steps, the gradient of their summed reward with respect to each step's
    /// action (a `k x act_dim` float64 array; one adjoint sweep). Differentiable flows only.
    fn reward_action_gradients<'py>(&self, py: Python<'py>, k: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let mut guard = self.env()?;
        let env: &mut dyn FlowEnv = &mut **guard;
        let g = detached(py, || env.reward_action_gradients(k))?.map_err(env_error)?;
        PyArray2::from_vec2(py, &g).map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }
}

/// `n` environments of one ID, stepped together on Rust threads: `VecEnv(id, n, level,
/// overrides)`. Each instance is the environment `Env` would make; instance `i` of a reset
/// with seeds `s` gets seed `s[i]`, so the results are those of `n` separate environments.
#[pyclass(module = "hgym._hgym")]
struct VecEnv {
    envs: Mutex<Vec<Box<dyn FlowEnv>>>,
    spec: Spec,
    keys: InfoKeys,
}

impl VecEnv {
    fn envs(&self) -> PyResult<std::sync::MutexGuard<'_, Vec<Box<dyn FlowEnv>>>> {
        self.envs
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the environments failed in an earlier call; make new ones"))
    }
}

/// Rows of `rows` (all of length `width`) as a float32 matrix.
fn matrix<'a, 'py>(py: Python<'py>, rows: impl ExactSizeIterator<Item = &'a [f64]>, width: usize) -> PyResult<Bound<'py, PyArray2<f32>>> {
    f32_array(py, [rows.len(), width], rows.flat_map(|r| r.iter().copied()))
}

#[pymethods]
impl VecEnv {
    #[new]
    #[pyo3(signature = (id, n, level = "coarse", overrides = None))]
    fn new(id: &str, n: usize, level: &str, overrides: Option<&str>) -> PyResult<Self> {
        if !(1..=4096).contains(&n) {
            return Err(PyValueError::new_err(format!("n must be 1 to 4096 environments, got {n}")));
        }
        let lvl = self::level(level)?;
        let spec = spec(id, overrides)?;
        let envs = (0..n).map(|_| make(&spec, lvl)).collect::<PyResult<Vec<_>>>()?;
        Ok(VecEnv {
            envs: Mutex::new(envs),
            spec,
            keys: InfoKeys::default(),
        })
    }

    #[getter]
    fn num_envs(&self) -> PyResult<usize> {
        Ok(self.envs()?.len())
    }

    #[getter]
    fn id(&self) -> String {
        self.spec.id().to_string()
    }

    /// `reset(seeds) -> (obs [n, obs_dim], infos)`: one seed per instance.
    fn reset<'py>(&self, py: Python<'py>, seeds: Vec<u64>) -> PyResult<(Bound<'py, PyArray2<f32>>, Infos<'py>)> {
        let mut guard = self.envs()?;
        let envs: &mut Vec<Box<dyn FlowEnv>> = &mut guard;
        if seeds.len() != envs.len() {
            return Err(PyValueError::new_err(format!(
                "{} seeds for {} environments: give one per environment",
                seeds.len(),
                envs.len()
            )));
        }
        let out: Vec<_> = detached(py, || {
            envs.par_iter_mut()
                .zip(seeds.par_iter())
                .map(|(e, &s)| e.reset(s))
                .collect::<Result<Vec<_>, _>>()
        })?
        .map_err(env_error)?;
        let obs = out.iter().map(|(o, _)| o.as_slice());
        let infos = out.iter().map(|(_, i)| self.keys.dict(py, i)).collect::<PyResult<_>>()?;
        Ok((matrix(py, obs, self.spec.obs_dim())?, infos))
    }

    /// `(low, high)` of one instance's observation space, float32.
    fn observation_bounds<'py>(&self, py: Python<'py>) -> PyResult<Bounds<'py>> {
        bounds(py, &self.envs()?[0].observation_space())
    }

    /// `(low, high)` of one instance's action space, float32.
    fn action_bounds<'py>(&self, py: Python<'py>) -> PyResult<Bounds<'py>> {
        bounds(py, &self.envs()?[0].action_space())
    }

    /// `step(actions [n, act_dim], resets) -> (obs, rewards, terminated, truncated, infos)`.
    /// `resets[i]` a seed: instance `i` resets with it instead of stepping (Gymnasium's
    /// next-step autoreset), and returns its first observation with reward 0.
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &self,
        py: Python<'py>,
        actions: PyReadonlyArray2<'py, f64>,
        resets: Vec<Option<u64>>,
    ) -> PyResult<(Bound<'py, PyArray2<f32>>, Vec<f64>, Vec<bool>, Vec<bool>, Vec<Bound<'py, PyDict>>)> {
        let shape = actions.shape().to_vec();
        let flat = actions.as_slice().map_err(|e| PyValueError::new_err(format!("the actions: {e}")))?;
        let mut guard = self.envs()?;
        let envs: &mut Vec<Box<dyn FlowEnv>> = &mut guard;
        let n = envs.len();
        let act_dim = self.spec.act_dim();
        if shape != [n, act_dim] || resets.len() != n {
            return Err(PyValueError::new_err(format!(
                "actions have shape {shape:?} and {} reset entries; the vector environment needs [{n}, {act_dim}] and {n}",
                resets.len()
            )));
        }
        let out = detached(py, || {
            envs.par_iter_mut()
                .zip(flat.par_chunks(act_dim.max(1)))
                .zip(resets.par_iter())
                .map(|((e, a), reset)| match reset {
                    Some(seed) => e.reset(*seed).map(|(obs, info)| hgym_agents::StepResult {
                        obs,
                        reward: 0.0,
                        terminated: false,
                        truncated: false,
                        info,
                    }),
                    None => e.step(a),
                })
                .collect::<Result<Vec<_>, _>>()
        })?
        .map_err(env_error)?;
        let infos = out.iter().map(|r| self.keys.dict(py, &r.info)).collect::<PyResult<_>>()?;
        Ok((
            matrix(py, out.iter().map(|r| r.obs.as_slice()), self.spec.obs_dim())?,
            out.iter().map(|r| r.reward).collect(),
            out.iter().map(|r| r.terminated).collect(),
            out.iter().map(|r| r.truncated).collect(),
            infos,
        ))
    }
}

/// Every registered ID with its spec's facts: a list of dicts.
#[pyfunction]
fn envs(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    hgym::env::registry::all()
        .iter()
        .map(|s| {
            let d = PyDict::new(py);
            d.set_item("id", s.id())?;
            d.set_item("family", s.family())?;
            d.set_item("solver", s.solver())?;
            d.set_item("dimension", s.dimension())?;
            d.set_item("reynolds", s.reynolds())?;
            d.set_item("obs_dim", s.obs_dim())?;
            d.set_item("act_dim", s.act_dim())?;
            d.set_item("control_interval", s.control_interval())?;
            d.set_item("differentiable", s.differentiable())?;
            d.set_item("spec_hash", s.hash())?;
            d.set_item("spec_toml", s.to_toml())?;
            Ok(d)
        })
        .collect()
}

#[pymodule]
fn _hgym(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Env>()?;
    m.add_class::<VecEnv>()?;
    m.add_function(wrap_pyfunction!(envs, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
