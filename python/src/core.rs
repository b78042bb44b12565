//! One environment: its spec (buildings, settings, observation) and the episode it steps, one
//! decision per step. Pure Rust (no Python types): the vector environment steps many of them on
//! threads.

use crate::buildings::{self, Named, Split};
use crate::graph::GraphConfig;
use crate::observe::{self, Action, Mode, Obs, Snapshot, Window};
use floorcast_worker::settings::{settings_from_json_text, Settings};
use floorcast_worker::{check_job, GivenSource, GivenStart, Job, RunSummary, StrategyRef};
use sim_core::explore::{BuiltIn, Episode, Event, Needs, Reply, RobotId};
use sim_core::{Pose, Vec2};
use std::sync::Arc;
use std::time::Instant;

/// How an episode's start is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum StartMode {
    /// The building's own start, as `floorcast explore` takes it.
    Building,
    /// Drawn from the seed, as a grid's random starts (`--start random`).
    Random,
}

/// What an environment is made of (from the Python side's spec, as JSON).
#[derive(Debug)]
pub(crate) struct Spec {
    pub(crate) buildings: Vec<Named>,
    pub(crate) settings: Settings,
    pub(crate) base: &'static BuiltIn,
    pub(crate) label: String,
    pub(crate) needs: Needs,
    pub(crate) mode: Mode,
    pub(crate) start: StartMode,
}

fn field<'a>(v: &'a serde_json::Value, key: &str) -> Option<&'a serde_json::Value> {
    v.get(key).filter(|x| !x.is_null())
}

fn usize_field(
    v: &serde_json::Value,
    key: &str,
    default: usize,
    range: (usize, usize),
) -> Result<usize, String> {
    match field(v, key) {
        None => Ok(default),
        Some(x) => x
            .as_u64()
            .map(|n| n as usize)
            .filter(|n| (range.0..=range.1).contains(n))
            .ok_or_else(|| {
                format!(
                    "{key}: {x} is not an integer from {} to {}",
                    range.0, range.1
                )
            }),
    }
}

impl Spec {
    /// The spec the JSON text describes, its buildings read (each error names its argument).
    pub(crate) fn from_json(text: &str) -> Result<Spec, String> {
        let v: serde_json::Value =
            serde_json::from_str(text).map_err(|e| format!("spec: not JSON: {e}"))?;
        let sources: Vec<String> = match field(&v, "buildings") {
            Some(serde_json::Value::String(s)) => vec![s.clone()],
            Some(serde_json::Value::Array(a)) => a
                .iter()
                .map(|x| x.as_str().map(str::to_string))
                .collect::<Option<_>>()
                .ok_or("buildings: expected a string or a list of strings (paths, globs, suite names, generator specs)")?,
            _ => return Err("buildings: required: a path, a glob, a suite's name or a generator spec (generate:KIND:AREA_M2:SEEDS), or a list of them".into()),
        };
        let split = Split::parse(field(&v, "split").map(|s| s.as_str().unwrap_or("?")))?;
        let mut list = Vec::new();
        for s in &sources {
            list.extend(buildings::resolve(s)?);
        }
        let all = list.len();
        list.retain(|b| split.keeps(&b.building));
        if list.is_empty() {
            return Err(format!(
                "buildings: no building left ({all} given, none in the {split:?} part of the split)"
            ));
        }
        let settings = match field(&v, "settings") {
            None => Settings::default(),
            Some(s) if s.is_object() => settings_from_json_text(&s.to_string())
                .map_err(|e| format!("settings: {e} (see `floorcast settings`)"))?,
            Some(s) => return Err(format!("settings: {s} is not a table of settings by name")),
        };
        settings
            .validate()
            .map_err(|e| format!("settings: {e} (see `floorcast settings`)"))?;
        if settings.charge_compute {
            return Err("settings: charge_compute = true is not supported by the environment (runs would depend on the machine's speed); leave it false".into());
        }
        let base_name = field(&v, "base")
            .and_then(|b| b.as_str())
            .unwrap_or("baseline");
        let base = BuiltIn::find(base_name).ok_or_else(|| {
            format!(
                "base: unknown strategy '{base_name}' (available: {})",
                floorcast_worker::strategy_names().join(", ")
            )
        })?;
        let label = field(&v, "label")
            .and_then(|b| b.as_str())
            .unwrap_or("python-policy")
            .to_string();
        let needs = parse_needs(&v)?;
        let mode = parse_mode(&v)?.with_laser_range(settings.laser_range_m);
        let start = match field(&v, "start")
            .and_then(|s| s.as_str())
            .unwrap_or("building")
        {
            "building" => StartMode::Building,
            "random" => StartMode::Random,
            other => {
                return Err(format!(
                    "start: '{other}'; expected \"building\" or \"random\""
                ))
            }
        };
        Ok(Spec {
            buildings: list,
            settings,
            base,
            label,
            needs,
            mode,
            start,
        })
    }
}

/// The needs a spec asks for (`needs`: "layout_gain", "layout").
pub(crate) fn parse_needs(v: &serde_json::Value) -> Result<Needs, String> {
    let mut needs = Needs::default();
    if let Some(list) = field(v, "needs") {
        for n in list.as_array().ok_or("needs: expected a list of strings")? {
            match n.as_str() {
                Some("layout_gain") => needs.layout_gain = true,
                Some("layout") => needs.layout = true,
                _ => {
                    return Err(format!(
                        "needs: {n} is not a need; expected \"layout_gain\" or \"layout\""
                    ))
                }
            }
        }
    }
    Ok(needs)
}

/// The observation mode a spec asks for (`observation`, `max_candidates`, `map_size`,
/// `map_cell_m`, `map_frame`).
pub(crate) fn parse_mode(v: &serde_json::Value) -> Result<Mode, String> {
    let mode = match field(v, "observation")
        .and_then(|o| o.as_str())
        .unwrap_or("candidates")
    {
        "candidates" => Mode::Candidates {
            max: usize_field(v, "max_candidates", 32, (1, 4096))?,
        },
        "map" => {
            let cell_m = match field(v, "map_cell_m") {
                None => 0.5,
                Some(x) => x
                    .as_f64()
                    .filter(|c| c.is_finite() && (0.01..=10.0).contains(c))
                    .ok_or_else(|| {
                        format!("map_cell_m: {x} is not a number from 0.01 to 10 (m)")
                    })?,
            };
            let egocentric = match field(v, "map_frame")
                .and_then(|f| f.as_str())
                .unwrap_or("egocentric")
            {
                "egocentric" => true,
                "global" => false,
                other => {
                    return Err(format!(
                        "map_frame: '{other}'; expected \"egocentric\" or \"global\""
                    ))
                }
            };
            Mode::Map {
                size: usize_field(v, "map_size", 64, (8, 1024))?,
                cell_m,
                egocentric,
            }
        }
        "graph" => {
            let range_m = match field(v, "graph_range_m") {
                None => f64::NAN,
                Some(x) => x
                    .as_f64()
                    .filter(|c| c.is_finite() && (0.1..=100.0).contains(c))
                    .ok_or_else(|| format!("graph_range_m: {x} is not a number from 0.1 to 100 (m)"))?,
            };
            let spacing_m = match field(v, "graph_spacing_m") {
                None => 1.5,
                Some(x) => x
                    .as_f64()
                    .filter(|c| c.is_finite() && (0.1..=20.0).contains(c))
                    .ok_or_else(|| format!("graph_spacing_m: {x} is not a number from 0.1 to 20 (m)"))?,
            };
            Mode::Graph(GraphConfig {
                nodes: usize_field(v, "graph_nodes", 360, (2, 4096))?,
                k: usize_field(v, "graph_k", 20, (2, 64))?,
                spacing_m,
                range_m,
            })
        }
        other => return Err(format!(
            "observation: '{other}' is not an observation mode; expected \"candidates\", \"map\" or \"graph\""
        )),
    };
    Ok(mode)
}

/// What a step (or reset) hands back.
#[derive(Debug, Clone)]
pub(crate) struct Out {
    pub(crate) obs: Obs,
    /// Raw reward terms: explored area gained (m2), simulated time elapsed (s), distance
    /// driven (m) since the previous decision; the explored fraction now.
    pub(crate) area_gain_m2: f64,
    pub(crate) elapsed_s: f64,
    pub(crate) driven_m: f64,
    pub(crate) explored_fraction: f64,
    pub(crate) explored_area_m2: f64,
    pub(crate) time_s: f64,
    /// The run ended (not by its time limit) / by its time limit.
    pub(crate) terminated: bool,
    pub(crate) truncated: bool,
    /// The end reason once over (`summary.json`'s words), and the summary.
    pub(crate) end_reason: Option<&'static str>,
    pub(crate) summary: Option<String>,
    pub(crate) building: String,
    pub(crate) seed: u64,
    pub(crate) decision: usize,
    pub(crate) attempt: usize,
}

/// The episode being stepped and what the environment keeps of it.
#[derive(Debug)]
struct Running {
    episode: Episode,
    building: usize,
    seed: u64,
    start: Option<GivenStart>,
    start_source: String,
    snap: Option<Snapshot>,
    obs: Obs,
    window: Option<Window>,
    trail: Vec<Vec2>,
    area_m2: f64,
    time_s: f64,
    path_m: f64,
    finished: bool,
    /// A step returned the end: the next step is an error.
    closed: bool,
    wall_s: f64,
}

/// One environment.
#[derive(Debug)]
pub(crate) struct Core {
    pub(crate) spec: Arc<Spec>,
    run: Option<Running>,
}

const ROBOT: RobotId = RobotId(0);

impl Core {
    pub(crate) fn new(spec: Arc<Spec>) -> Core {
        Core { spec, run: None }
    }

    fn job(&self, building: usize, seed: u64, start: Option<GivenStart>) -> Job<'_> {
        let b = &self.spec.buildings[building];
        Job {
            building: &b.building,
            building_name: b.name.clone(),
            strategy: StrategyRef::BuiltIn(self.spec.base),
            seed,
            settings: self.spec.settings.clone(),
            start,
            snapshot_fractions: Vec::new(),
        }
    }

    /// A new episode: building `building` (default: the seed's, `seed % buildings`), the start
    /// `start` (default: the spec's start mode).
    pub(crate) fn reset(
        &mut self,
        seed: u64,
        building: Option<usize>,
        start: Option<Pose>,
    ) -> Result<Out, String> {
        self.guarded(|c| c.reset_inner(seed, building, start))
    }

    /// Answers the pending decision with `action` and runs to the next one.
    pub(crate) fn step(&mut self, action: Action) -> Result<Out, String> {
        self.guarded(|c| c.step_inner(action))
    }

    /// `f`, a panic of the simulation (a bug) caught as an error that ends the episode.
    fn guarded(&mut self, f: impl FnOnce(&mut Core) -> Result<Out, String>) -> Result<Out, String> {
        match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(self))) {
            Ok(r) => r,
            Err(p) => {
                self.run = None;
                Err(format!(
                    "internal: the simulation failed (a bug in floorcast, please report it): {}; call reset()",
                    floorcast_worker::panic_message(&*p)
                ))
            }
        }
    }

    fn reset_inner(
        &mut self,
        seed: u64,
        building: Option<usize>,
        start: Option<Pose>,
    ) -> Result<Out, String> {
        let n = self.spec.buildings.len();
        let building = match building {
            Some(b) if b < n => b,
            Some(b) => return Err(format!("options['building']: {b} is not a building of the environment (it has {n}: 0 to {})", n - 1)),
            None => (seed % n as u64) as usize,
        };
        let named = &self.spec.buildings[building];
        let given = match (start, self.spec.start) {
            (Some(p), _) => Some(GivenStart {
                pose: p,
                source: GivenSource::CommandLine,
            }),
            (None, StartMode::Building) => None,
            (None, StartMode::Random) => Some(GivenStart {
                pose: named
                    .building
                    .random_start(self.spec.settings.robot_radius_m, seed, 0)
                    .map_err(|e| format!("start: building {}: {e}", named.name))?,
                source: GivenSource::Random,
            }),
        };
        let job = self.job(building, seed, given.clone());
        let (config, start_pose, source) = check_job(&job).map_err(|e| {
            let what = if start.is_some() {
                "options['start']"
            } else {
                "buildings"
            };
            format!("{what}: {e}")
        })?;
        let t0 = Instant::now();
        let episode =
            Episode::with_policy(&named.building, start_pose, config, seed, self.spec.needs);
        self.run = Some(Running {
            episode,
            building,
            seed,
            start: given,
            start_source: source,
            snap: None,
            obs: observe::empty(self.spec.mode),
            window: None,
            trail: Vec::new(),
            area_m2: 0.0,
            time_s: 0.0,
            path_m: 0.0,
            finished: false,
            closed: false,
            wall_s: 0.0,
        });
        let mut out = self.advance()?;
        if let Some(r) = self.run.as_mut() {
            r.wall_s += t0.elapsed().as_secs_f64();
        }
        // The reset's observation starts the reward's count.
        out.area_gain_m2 = 0.0;
        out.elapsed_s = 0.0;
        out.driven_m = 0.0;
        Ok(out)
    }

    fn step_inner(&mut self, action: Action) -> Result<Out, String> {
        let mode = self.spec.mode;
        let run = self
            .run
            .as_mut()
            .ok_or("step: call reset() before step()")?;
        if run.closed {
            return Err("step: the episode is over (terminated or truncated); call reset()".into());
        }
        let t0 = Instant::now();
        if run.snap.is_some() {
            let reply = observe::reply(mode, &run.obs, run.window, action)?;
            run.episode
                .answer(ROBOT, reply)
                .map_err(|e| format!("step: {e}"))?;
        }
        // (An episode that ended before its first decision takes any action once.)
        let out = self.advance();
        if let Some(r) = self.run.as_mut() {
            r.wall_s += t0.elapsed().as_secs_f64();
            r.closed = r.finished;
        }
        out
    }

    /// Runs the episode to its next decision (a goal point without a path falls back to the
    /// candidate nearest to it) or its end.
    fn advance(&mut self) -> Result<Out, String> {
        let mode = self.spec.mode;
        let run = self.run.as_mut().ok_or("step: call reset() first")?;
        if !run.finished {
            loop {
                match run.episode.advance() {
                    Event::Decide(r) => {
                        let view = run
                            .episode
                            .view(r)
                            .ok_or("internal: a decision without a view")?;
                        let snap = Snapshot::of(&view);
                        if let (Some(p), true) = (snap.unreachable_goal, mode.points()) {
                            let id = observe::nearest_candidate(&snap, p)
                                .ok_or("internal: a decision without candidates")?;
                            run.episode
                                .answer(r, Reply::Choose(id))
                                .map_err(|e| format!("internal: {e}"))?;
                            continue;
                        }
                        observe::extend_trail(&mut run.trail, &snap);
                        let map = mode.needs_map().then_some(view.map);
                        run.obs = observe::observe(mode, &snap, map, &run.trail);
                        run.window = Some(Window::of(mode, snap.pose, Some(view.map.frame)));
                        run.snap = Some(snap);
                        break;
                    }
                    Event::Progress(..) => {}
                    Event::Ended(..) => {}
                    Event::Finished => {
                        run.finished = true;
                        break;
                    }
                }
            }
        }
        let (area, fraction) = run.episode.explored(ROBOT).unwrap_or((0.0, 0.0));
        let time_s = run.episode.time_s();
        let path_m = run.episode.world().path_length_m(ROBOT);
        let (area, fraction) = match (run.finished, run.episode.result()) {
            (true, Some(r)) => (r.explored_area_m2, r.explored_fraction),
            _ => (area, fraction),
        };
        let mut out = Out {
            obs: run.obs.clone(),
            area_gain_m2: area - run.area_m2,
            elapsed_s: time_s - run.time_s,
            driven_m: path_m - run.path_m,
            explored_fraction: fraction,
            explored_area_m2: area,
            time_s,
            terminated: false,
            truncated: false,
            end_reason: None,
            summary: None,
            building: self.spec.buildings[run.building].name.clone(),
            seed: run.seed,
            decision: run.snap.as_ref().map_or(0, |s| s.decision),
            attempt: run.snap.as_ref().map_or(0, |s| s.attempt),
        };
        run.area_m2 = area;
        run.time_s = time_s;
        run.path_m = path_m;
        if run.finished {
            let result = run
                .episode
                .result()
                .ok_or("internal: a finished episode without its result")?;
            let reason = result.end_reason;
            out.truncated = reason == sim_core::explore::EndReason::TimeLimit;
            out.terminated = !out.truncated;
            out.end_reason = Some(reason.as_str());
            let (building, seed, start, source, wall_s) = (
                run.building,
                run.seed,
                run.start.clone(),
                run.start_source.clone(),
                run.wall_s,
            );
            let result = result.clone();
            let job = self.job(building, seed, start);
            let mut summary = RunSummary::new(&job, &result, &source, wall_s);
            summary.strategy = self.spec.label.clone();
            out.summary = Some(serde_json::to_string(&summary).map_err(|e| e.to_string())?);
        }
        Ok(out)
    }
}

impl Core {
    /// Whether `action` is one the pending decision takes (what [`Core::step`] would refuse).
    pub(crate) fn check(&self, action: Action) -> Result<(), String> {
        let run = self
            .run
            .as_ref()
            .ok_or("step: call reset() before step()")?;
        if run.closed {
            return Err("the episode is over (terminated or truncated); call reset()".into());
        }
        if run.snap.is_none() {
            return Ok(());
        }
        observe::reply(self.spec.mode, &run.obs, run.window, action).map(|_| ())
    }
}
