//! The native module of the `floorcast` Python package (`floorcast._native`): floorcast's
//! episode stepped one decision at a time from Python, alone ([`Env`]) or many on Rust threads
//! with the GIL released ([`VecEnv`]), and the observations of the strategy protocol's
//! messages for a policy run as a strategy ([`Observer`]). The Python package (python/floorcast)
//! wraps them in gymnasium's API; arrays cross as copied bytes that it wraps in numpy.

mod buildings;
mod core;
mod graph;
mod observe;
mod pool;
mod serve;

use crate::core::{Core, Out, Spec};
use crate::observe::{Action, Obs, CHANNELS, FEATURES};
use crate::pool::{Input, Pool};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyByteArray, PyDict, PyList};
use sim_core::Pose;
use std::sync::Arc;

/// A refused argument as ValueError; a bug of floorcast's (an error beginning "internal:") as
/// RuntimeError.
fn value_error(e: String) -> PyErr {
    match e.find("internal: ") {
        Some(at) => PyRuntimeError::new_err(format!("{}{}", &e[..at], &e[at + 10..])),
        None => PyValueError::new_err(e),
    }
}

/// An observation's arrays: `[(key, dtype, shape, bytearray)]`.
fn obs_list<'py>(py: Python<'py>, obs: &Obs) -> PyResult<Bound<'py, PyList>> {
    let list = PyList::empty(py);
    for (key, dtype, shape, bytes) in &obs.arrays {
        list.append((*key, *dtype, shape.clone(), PyByteArray::new(py, bytes)))?;
    }
    Ok(list)
}

/// A step's output as a dict (see `floorcast/_env.py`).
fn out_dict<'py>(py: Python<'py>, o: &Out) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("obs", obs_list(py, &o.obs)?)?;
    d.set_item("area_gain_m2", o.area_gain_m2)?;
    d.set_item("elapsed_s", o.elapsed_s)?;
    d.set_item("driven_m", o.driven_m)?;
    d.set_item("explored_fraction", o.explored_fraction)?;
    d.set_item("explored_area_m2", o.explored_area_m2)?;
    d.set_item("time_s", o.time_s)?;
    d.set_item("terminated", o.terminated)?;
    d.set_item("truncated", o.truncated)?;
    d.set_item("end_reason", o.end_reason)?;
    d.set_item("summary", o.summary.as_deref())?;
    d.set_item("building", &o.building)?;
    d.set_item("seed", o.seed)?;
    d.set_item("decision", o.decision)?;
    d.set_item("attempt", o.attempt)?;
    d.set_item("candidates", o.obs.ids.len())?;
    Ok(d)
}

fn action_of(index: Option<i64>, point: Option<(f64, f64)>) -> PyResult<Action> {
    match (index, point) {
        (Some(i), None) => Ok(Action::Index(i)),
        (None, Some((x, y))) => Ok(Action::Point([x, y])),
        _ => Err(value_error("action: give an index or a point".into())),
    }
}

fn start_of(start: Option<(f64, f64, f64)>) -> PyResult<Option<Pose>> {
    match start {
        Some((x, y, t)) if x.is_finite() && y.is_finite() && t.is_finite() => {
            Ok(Some(Pose::new(x, y, t)))
        }
        Some(_) => Err(value_error(
            "options['start']: expected three finite numbers [x m, y m, theta rad]".into(),
        )),
        None => Ok(None),
    }
}

/// One environment (see `floorcast.ExploreEnv`).
#[pyclass(module = "floorcast._native")]
#[derive(Debug)]
struct Env {
    core: Core,
}

#[pymethods]
impl Env {
    /// An environment of the spec (JSON text); ValueError naming the argument when it is bad.
    #[new]
    fn new(py: Python<'_>, spec: &str) -> PyResult<Self> {
        let spec = py.detach(|| Spec::from_json(spec)).map_err(value_error)?;
        Ok(Env {
            core: Core::new(Arc::new(spec)),
        })
    }

    #[pyo3(signature = (seed, building=None, start=None))]
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        seed: u64,
        building: Option<usize>,
        start: Option<(f64, f64, f64)>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let start = start_of(start)?;
        let core = &mut self.core;
        let out = py
            .detach(|| core.reset(seed, building, start))
            .map_err(value_error)?;
        out_dict(py, &out)
    }

    #[pyo3(signature = (index=None, point=None))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        index: Option<i64>,
        point: Option<(f64, f64)>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let action = action_of(index, point)?;
        let core = &mut self.core;
        let out = py.detach(|| core.step(action)).map_err(value_error)?;
        out_dict(py, &out)
    }

    /// The names of the environment's buildings, in order.
    fn building_names(&self) -> Vec<String> {
        self.core
            .spec
            .buildings
            .iter()
            .map(|b| b.name.clone())
            .collect()
    }
}

/// Many environments of one spec, stepped on `threads` Rust threads with the GIL released
/// (see `floorcast.VectorExplore`). Episode `k` of environment `i` after `reset(seed)` has
/// seed `seed + i + k * num_envs`; an environment whose episode ended is reset at its next
/// step (gymnasium's next-step autoreset).
#[pyclass(module = "floorcast._native")]
#[derive(Debug)]
struct VecEnv {
    spec: Arc<Spec>,
    pool: Pool,
    n: usize,
    next_seed: Vec<u64>,
    pending_reset: Vec<bool>,
}

#[pymethods]
impl VecEnv {
    #[new]
    fn new(py: Python<'_>, spec: &str, num_envs: usize, threads: usize) -> PyResult<Self> {
        if !(1..=4096).contains(&num_envs) {
            return Err(value_error(format!(
                "num_envs: {num_envs} is not from 1 to 4096"
            )));
        }
        if !(1..=256).contains(&threads) {
            return Err(value_error(format!(
                "threads: {threads} is not from 1 to 256"
            )));
        }
        let spec = Arc::new(py.detach(|| Spec::from_json(spec)).map_err(value_error)?);
        let cores = (0..num_envs)
            .map(|_| Core::new(Arc::clone(&spec)))
            .collect();
        Ok(VecEnv {
            spec,
            pool: Pool::new(cores, threads).map_err(value_error)?,
            n: num_envs,
            next_seed: vec![0; num_envs],
            pending_reset: vec![false; num_envs],
        })
    }

    fn reset<'py>(&mut self, py: Python<'py>, seed: u64) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let n = self.n as u64;
        let seeds: Vec<u64> = (0..n).map(|i| seed.wrapping_add(i)).collect();
        let pool = &self.pool;
        let outs = py
            .detach(|| pool.round(seeds.iter().map(|&s| Input::Reset(s)).collect()))
            .map_err(value_error)?;
        for (i, s) in seeds.iter().enumerate() {
            self.next_seed[i] = s.wrapping_add(n);
            self.pending_reset[i] = false;
        }
        outs.iter()
            .map(|o| out_dict(py, o.as_ref().map_err(|e| value_error(e.clone()))?))
            .collect()
    }

    /// One step of every environment: `indices` (candidates, graph) or `points` (map), one per
    /// environment. Every action is checked before any environment moves.
    #[pyo3(signature = (indices=None, points=None))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        indices: Option<Vec<i64>>,
        points: Option<Vec<(f64, f64)>>,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let n = self.n;
        let actions: Vec<Action> = match (indices, points) {
            (Some(i), None) if i.len() == n => i.into_iter().map(Action::Index).collect(),
            (None, Some(p)) if p.len() == n => {
                p.into_iter().map(|(x, y)| Action::Point([x, y])).collect()
            }
            _ => {
                return Err(value_error(format!(
                    "actions: expected one action per environment ({n})"
                )))
            }
        };
        let pool = &self.pool;
        for (i, c) in pool.check(&actions).into_iter().enumerate() {
            if !self.pending_reset[i] {
                c.map_err(|e| value_error(format!("actions[{i}]: {e}")))?;
            }
        }
        let inputs: Vec<Input> = actions
            .into_iter()
            .enumerate()
            .map(|(i, a)| match self.pending_reset[i] {
                true => Input::Reset(self.next_seed[i]),
                false => Input::Step(a),
            })
            .collect();
        let outs = py.detach(|| pool.round(inputs)).map_err(value_error)?;
        let mut dicts = Vec::with_capacity(n);
        for (i, o) in outs.into_iter().enumerate() {
            let o = o.map_err(|e| value_error(format!("environment {i}: {e}")))?;
            if self.pending_reset[i] {
                self.next_seed[i] = self.next_seed[i].wrapping_add(n as u64);
                self.pending_reset[i] = false;
                let d = out_dict(py, &o)?;
                d.set_item("autoreset", true)?;
                dicts.push(d);
            } else {
                self.pending_reset[i] = o.terminated || o.truncated;
                dicts.push(out_dict(py, &o)?);
            }
        }
        Ok(dicts)
    }

    fn building_names(&self) -> Vec<String> {
        self.spec.buildings.iter().map(|b| b.name.clone()).collect()
    }
}

/// The observations of a run seen through the strategy protocol (see `floorcast.serve`).
#[pyclass(module = "floorcast._native")]
#[derive(Debug)]
struct Observer {
    inner: serve::Observer,
}

#[pymethods]
impl Observer {
    /// An observer for the spec's observation mode (JSON text: `observation`,
    /// `max_candidates`, `map_*`).
    #[new]
    fn new(spec: &str) -> PyResult<Self> {
        let v: serde_json::Value =
            serde_json::from_str(spec).map_err(|e| value_error(format!("spec: not JSON: {e}")))?;
        let mode = core::parse_mode(&v).map_err(value_error)?;
        Ok(Observer {
            inner: serve::Observer::new(mode),
        })
    }

    /// A run begins (the run message, as JSON text).
    fn begin(&mut self, run: &str) -> PyResult<()> {
        let v: serde_json::Value = serde_json::from_str(run)
            .map_err(|e| value_error(format!("run message: not JSON: {e}")))?;
        self.inner.begin(&v).map_err(value_error)
    }

    /// A decide message (JSON text): `(reply, None)` when the observer answers it itself,
    /// else `(None, obs)`.
    fn decide<'py>(
        &mut self,
        py: Python<'py>,
        message: &str,
    ) -> PyResult<(Option<String>, Option<Bound<'py, PyList>>)> {
        let v: serde_json::Value = serde_json::from_str(message)
            .map_err(|e| value_error(format!("decide message: not JSON: {e}")))?;
        match self.inner.decide(&v).map_err(value_error)? {
            Some(r) => Ok((Some(serve::reply_json(&r)), None)),
            None => Ok((None, Some(obs_list(py, &self.inner.obs)?))),
        }
    }

    /// The reply (a JSON line) the action makes at the pending decision.
    #[pyo3(signature = (index=None, point=None))]
    fn reply(&self, index: Option<i64>, point: Option<(f64, f64)>) -> PyResult<String> {
        let r = self
            .inner
            .reply(action_of(index, point)?)
            .map_err(value_error)?;
        Ok(serve::reply_json(&r))
    }
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("FEATURES", FEATURES.to_vec())?;
    m.add("CHANNELS", CHANNELS.to_vec())?;
    m.add("TEST_SHARE", buildings::TEST_SHARE)?;
    m.add_class::<Env>()?;
    m.add_class::<VecEnv>()?;
    m.add_class::<Observer>()?;
    Ok(())
}
