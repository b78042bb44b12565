//! A policy as a strategy: the observations of the strategy protocol's decide messages, made
//! by the code that makes the environment's (`floorcast.serve` drives it).

use crate::observe::{self, Action, Cand, Mode, Obs, Snapshot, Window};
use serde_json::Value;
use sim_core::explore::Reply;
use sim_core::grid::{GridFrame, Occupancy, OccupancyGrid};
use sim_core::{Pose, Vec2};

/// The protocol's side of one run: the map rebuilt from the decide messages' changes, the
/// trail, and the decision pending.
#[derive(Debug)]
pub(crate) struct Observer {
    pub(crate) mode: Mode,
    map: Option<OccupancyGrid>,
    trail: Vec<Vec2>,
    snap: Option<Snapshot>,
    pub(crate) obs: Obs,
    window: Option<Window>,
}

fn num(v: &Value, key: &str) -> Result<f64, String> {
    v.get(key)
        .and_then(Value::as_f64)
        .ok_or_else(|| format!("field '{key}': expected a number"))
}

fn pair(v: &Value, key: &str) -> Result<[f64; 2], String> {
    match v.get(key).and_then(Value::as_array).map(Vec::as_slice) {
        Some([a, b]) => Ok([
            a.as_f64()
                .ok_or_else(|| format!("field '{key}': expected numbers"))?,
            b.as_f64()
                .ok_or_else(|| format!("field '{key}': expected numbers"))?,
        ]),
        _ => Err(format!("field '{key}': expected [x, y]")),
    }
}

fn index(v: &Value, key: &str) -> Option<usize> {
    v.get(key).and_then(Value::as_u64).map(|n| n as usize)
}

impl Observer {
    pub(crate) fn new(mode: Mode) -> Observer {
        Observer {
            mode,
            map: None,
            trail: Vec::new(),
            snap: None,
            obs: observe::empty(mode),
            window: None,
        }
    }

    /// A new run (the run message): the map all unknown, no trail.
    pub(crate) fn begin(&mut self, run: &Value) -> Result<(), String> {
        let m = run.get("map").ok_or("run message: no field 'map'")?;
        let origin = pair(m, "origin").map_err(|e| format!("run message: map.{e}"))?;
        let cells = |k: &str| {
            index(m, k)
                .filter(|&n| n > 0 && n <= 1 << 20)
                .ok_or_else(|| format!("run message: map.{k}: expected a positive integer"))
        };
        let (w, h) = (cells("width")?, cells("height")?);
        if w * h > 1 << 28 {
            return Err("run message: map too large".into());
        }
        let frame = GridFrame::new(
            Vec2::new(origin[0], origin[1]),
            num(m, "resolution_m").map_err(|e| format!("run message: map.{e}"))?,
            w as u32,
            h as u32,
        );
        self.map = Some(OccupancyGrid::filled(frame, Occupancy::Unknown));
        if let Mode::Graph(g) = self.mode {
            if g.range_m.is_nan() {
                let laser = run
                    .get("settings")
                    .and_then(|s| s.get("laser_range_m"))
                    .and_then(Value::as_f64)
                    .ok_or("run message: settings.laser_range_m: expected a number (the graph's sensing range is drawn from it)")?;
                self.mode = self.mode.with_laser_range(laser);
            }
        }
        self.trail.clear();
        self.snap = None;
        Ok(())
    }

    /// The decision a decide message asks for. `Some(reply)` when the observer answers it
    /// itself (a goal point of the map mode without a path: the candidate nearest to it, as
    /// the environment does), else `None` and the observation in `self.obs`.
    pub(crate) fn decide(&mut self, d: &Value) -> Result<Option<Reply>, String> {
        self.decide_inner(d)
            .map_err(|e| match e.starts_with("decide message") {
                true => e,
                false => format!("decide message: {e}"),
            })
    }

    fn decide_inner(&mut self, d: &Value) -> Result<Option<Reply>, String> {
        if let (Some(changes), Some(map)) = (d.get("map_changes"), self.map.as_mut()) {
            for (key, state) in [
                ("free", Occupancy::Free),
                ("occupied", Occupancy::Occupied),
                ("unknown", Occupancy::Unknown),
            ] {
                for i in changes
                    .get(key)
                    .and_then(Value::as_array)
                    .into_iter()
                    .flatten()
                {
                    let i = i
                        .as_u64()
                        .map(|i| i as usize)
                        .filter(|&i| i < map.data.len());
                    let i = i.ok_or_else(|| {
                        format!("decide message: map_changes.{key}: a cell outside the map")
                    })?;
                    map.data[i] = state;
                }
            }
        }
        let pose = match d.get("pose").and_then(Value::as_array).map(Vec::as_slice) {
            Some([x, y, t]) => Pose::new(
                x.as_f64().unwrap_or(f64::NAN),
                y.as_f64().unwrap_or(f64::NAN),
                t.as_f64().unwrap_or(f64::NAN),
            ),
            _ => return Err("decide message: field 'pose': expected [x, y, theta]".into()),
        };
        let mut candidates = Vec::new();
        for c in d
            .get("candidates")
            .and_then(Value::as_array)
            .ok_or("decide message: no candidates")?
        {
            let goal = pair(c, "goal").map_err(|e| format!("decide message: a candidate's {e}"))?;
            candidates.push(Cand {
                id: index(c, "id").ok_or("decide message: a candidate without an id")?,
                goal: Vec2::new(goal[0], goal[1]),
                frontier_cells: index(c, "frontier_cells").unwrap_or(0),
                path_m: num(c, "path_m")?,
                straight_m: num(c, "straight_m")?,
                gain_m2: num(c, "gain_m2")?,
                layout_gain_m2: c.get("layout_gain_m2").and_then(Value::as_f64),
                room: index(c, "room"),
            });
        }
        let snap = Snapshot {
            decision: index(d, "decision").unwrap_or(0),
            attempt: index(d, "attempt").unwrap_or(0),
            time_s: num(d, "time_s")?,
            pose,
            candidates,
            robot_room: index(d, "robot_room"),
            unreachable_goal: d
                .get("unreachable_goal")
                .filter(|v| !v.is_null())
                .map(|_| {
                    pair(d, "unreachable_goal")
                        .map(|p| Vec2::new(p[0], p[1]))
                        .map_err(|e| format!("decide message: {e}"))
                })
                .transpose()?,
        };
        if let (Some(p), true) = (snap.unreachable_goal, self.mode.points()) {
            return Ok(observe::nearest_candidate(&snap, p).map(Reply::Choose));
        }
        observe::extend_trail(&mut self.trail, &snap);
        self.obs = observe::observe(self.mode, &snap, self.map.as_ref(), &self.trail);
        self.window = Some(Window::of(
            self.mode,
            snap.pose,
            self.map.as_ref().map(|m| m.frame),
        ));
        self.snap = Some(snap);
        Ok(None)
    }

    /// The reply an action makes at the pending decision.
    pub(crate) fn reply(&self, action: Action) -> Result<Reply, String> {
        observe::reply(self.mode, &self.obs, self.window, action)
    }
}

/// A reply as the protocol's JSON line.
pub(crate) fn reply_json(r: &Reply) -> String {
    match r {
        Reply::Choose(id) => format!("{{\"type\":\"choose\",\"id\":{id}}}"),
        Reply::Goal(p) => serde_json::json!({"type": "goal", "point": [p.x, p.y]}).to_string(),
        Reply::Stop => "{\"type\":\"stop\"}".into(),
        _ => "{\"type\":\"pass\"}".into(),
    }
}
