//! floorcast's compliance checker (`floorcast strategy check`): a program run through a
//! scripted session that touches every message and rule of the protocol ([`check_program`]).

use sim_core::explore::{DecisionView, Policy, Reply, RunEnd};

use super::program::StrategyProgram;
use super::protocol::{run_message, Hello};
use super::session::{ExternalStrategy, StrategyError, StrategyStats};

/// One check of [`check_program`]: what was checked, and what the program did (`Err`: how it
/// broke the protocol).
#[derive(Debug, Clone, PartialEq)]
pub struct Check {
    pub what: &'static str,
    pub outcome: Result<String, String>,
}

/// Runs a program through a scripted session that touches every message and rule of the
/// protocol (the handshake, a run, a decision and a second attempt at it, a decision with one
/// candidate whose id is not its position, the end, exiting when stdin closes) and returns
/// every check, stopping at the first the program fails, and the protocol version the program
/// speaks (`None`: its hello failed): floorcast's compliance checker. The session is the
/// version the program answers with (1 or 2: in 2, the ready reply's needs are the run's).
pub fn check_program(program: &StrategyProgram) -> (Vec<Check>, Option<u64>) {
    let mut checks = Vec::new();
    let mut push = |what, outcome: Result<String, String>| {
        let ok = outcome.is_ok();
        checks.push(Check { what, outcome });
        ok
    };
    let mut s = match ExternalStrategy::start(program) {
        Ok(s) => s,
        Err(e) => {
            push("hello", Err(e.what));
            return (checks, None);
        }
    };
    let protocol = Some(s.hello().protocol);
    push("hello", Ok(hello_text(s.hello())));
    let map = check_room();
    let settings = crate::Settings::default();
    let begun = s.begin(
        run_message(
            "check",
            "0",
            1,
            CHECK_START,
            &settings,
            &program.params,
            &map.frame,
        ),
        false,
    );
    let ready = begun
        .map(|()| match s.hello().protocol {
            1 => "ready".into(),
            _ => format!("ready, {}", needs_text(s.hello())),
        })
        .map_err(|e| e.what);
    if !push("run", ready) {
        return (checks, protocol);
    }
    if !check_decisions(&mut s, &map, &mut push) {
        return (checks, protocol);
    }
    s.end(&RunEnd {
        reason: sim_core::explore::EndReason::Complete,
        exploration_time_s: 3.0,
        explored_fraction: 1.0,
        decisions: 2,
    });
    let (what, outcome) = exit_check(s.finish());
    push(what, outcome);
    (checks, protocol)
}

/// Where the check's robot stands.
const CHECK_START: sim_core::Pose = sim_core::Pose::new(2.4, 0.7, 0.0);
/// Where it stands at the second decision: inside the predicted room of [`check_room_view`].
const IN_THE_ROOM: sim_core::Pose = sim_core::Pose::new(3.6, 0.7, 0.0);

/// The check's decisions: one of three candidates, a second attempt without the one chosen,
/// then one candidate whose id (7) is not its position, the robot moved into the predicted room
/// (protocol 2's `robot_room` is then 0, before `null`). Each check is `push`ed; whether all
/// passed.
fn check_decisions(
    s: &mut ExternalStrategy,
    map: &sim_core::grid::OccupancyGrid,
    push: &mut impl FnMut(&'static str, Result<String, String>) -> bool,
) -> bool {
    use sim_core::explore::CandidateView;
    let h = s.hello().clone();
    let candidate = |id, x, y, path_m, gain_m2| {
        check_candidate(map, CHECK_START, &h, id, (x, y), path_m, gain_m2)
    };
    let three = [
        candidate(0, 23, 3, 2.2, 4.0),
        candidate(2, 23, 4, 2.3, 3.5),
        candidate(5, 1, 3, 2.0, 1.0),
    ];
    let rooms = [check_room_view(map)];
    let view = |decision, attempt, candidates| DecisionView {
        decision,
        attempt,
        time_s: 1.0 + decision as f64,
        pose: if decision == 0 {
            CHECK_START
        } else {
            IN_THE_ROOM
        },
        candidates,
        unreachable_goal: None,
        layout: h.needs_layout.then_some(sim_core::explore::LayoutView {
            number: 1,
            rooms: &rooms,
        }),
        map,
        between_m: None,
        team: None,
    };
    let mut ask = |what, v: &DecisionView<'_>| {
        let (r, _) = s.decide(v);
        let outcome = match s.protocol_error() {
            Some(e) => Err(e.to_string()),
            None => Ok(reply_text(&r)),
        };
        (push(what, outcome), r)
    };
    let (ok, first) = ask("decide", &view(0, 0, &three));
    if !ok {
        return false;
    }
    // The chosen candidate "had no path": asked again without it.
    let rest: Vec<CandidateView> = match first {
        Reply::Choose(id) => three.iter().filter(|c| c.id != id).copied().collect(),
        _ => three[1..].to_vec(),
    };
    if !ask("decide again (attempt 1)", &view(0, 1, &rest)).0 {
        return false;
    }
    let one = [candidate(7, 1, 2, 2.1, 0.5)];
    ask("decide with one candidate (id 7)", &view(1, 0, &one)).0
}

/// What the hello of a program says: its name, protocol and needs.
fn hello_text(h: &Hello) -> String {
    format!(
        "name '{}', protocol {}, {}",
        h.name,
        h.protocol,
        needs_text(h)
    )
}

/// A program's needs as the check prints them.
fn needs_text(h: &Hello) -> String {
    let mut needs: Vec<&str> = Vec::new();
    if h.needs_layout_gain {
        needs.push("layout_gain");
    }
    if h.needs_layout {
        needs.push("layout");
    }
    if h.needs_map {
        needs.push("map");
    }
    format!("needs [{}]", needs.join(", "))
}

/// The check's map: a room of 4 x 2 m seen from its middle, unknown beyond its open ends.
fn check_room() -> sim_core::grid::OccupancyGrid {
    sim_core::grid::OccupancyGrid::from_ascii(
        "
        ????????????????????????
        ?######################?
        ?.......................
        ?.......................
        ?......................?
        ?......................?
        ?######################?
        ",
        0.2,
    )
}

/// A candidate of the check at cell `(x, y)` of `map`, with what the program's needs ask for.
fn check_candidate(
    map: &sim_core::grid::OccupancyGrid,
    start: sim_core::Pose,
    h: &Hello,
    id: usize,
    (x, y): (i32, i32),
    path_m: f64,
    gain_m2: f64,
) -> sim_core::explore::CandidateView {
    let point = map.frame.world_from_cell(sim_core::grid::Cell::new(x, y));
    sim_core::explore::CandidateView {
        id,
        cell: sim_core::grid::Cell::new(x, y),
        point,
        goal: point,
        frontier_cells: 4,
        distance_m: path_m,
        path_m,
        straight_m: (point - start.position()).norm(),
        gain_m2,
        layout_gain_m2: h.needs_layout_gain.then_some(gain_m2 * 0.5),
        // Room 0 below covers cells x >= 13 (2.6 m to 4.8 m at 0.2 m per cell).
        room: h.needs_layout.then_some(0).filter(|_| x > 12),
    }
}

/// With the need "layout": one predicted room, the right half of the check's room, open.
fn check_room_view(map: &sim_core::grid::OccupancyGrid) -> sim_core::explore::RoomView {
    sim_core::explore::RoomView {
        polygon: [(2.6, 0.4), (4.8, 0.4), (4.8, 1.2), (2.6, 1.2)]
            .iter()
            .map(|&(x, y)| map.frame.origin_m + sim_core::Vec2::new(x, y))
            .collect(),
        state: sim_core::explore::RoomState::Open,
        predicted: true,
        area_m2: 1.76,
        observed_area_m2: 1.6,
        unknown_area_m2: 0.16,
    }
}

/// A reply as the check prints it.
fn reply_text(r: &Reply) -> String {
    match r {
        Reply::Choose(id) => format!("choose {id}"),
        Reply::Rank(ids) => format!("rank {ids:?}"),
        Reply::Goal(p) => format!("goal [{}, {}]", p.x, p.y),
        Reply::Drop(ids) => format!("drop {ids:?}"),
        Reply::Stop => "stop".into(),
        Reply::Pass => "pass".into(),
        Reply::Fail => "failed".into(),
    }
}

/// The check's last step: the program exits when its stdin closes, leaving nothing running.
fn exit_check(
    finished: Result<StrategyStats, StrategyError>,
) -> (&'static str, Result<String, String>) {
    let what = "end, then exit when stdin closes";
    let outcome = match finished {
        Ok(stats) if stats.exited && stats.left_behind => Err("exited, but left processes it started running (floorcast killed them): a strategy ends every process it starts before it exits".into()),
        Ok(stats) if stats.exited => Ok("exited".into()),
        Ok(_) => Err("did not exit within 1 s of its stdin closing (it was killed)".into()),
        Err(e) => Err(e.what),
    };
    (what, outcome)
}
