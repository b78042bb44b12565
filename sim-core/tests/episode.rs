//! An [`Episode`] driven from outside, through its public interface only (issue 79): answered by
//! a hand-written nearest-frontier rule it is the built-in `nearest` run, decision for decision
//! and pose for pose; moved to another thread between steps it is the same run; calls it cannot
//! take are errors, not panics; a team of robots shares the world, each deciding and scored on
//! its own.

// Integration tests run at the edge: they spawn threads, which the kernel itself may not
// (sim-core/clippy.toml).
#![allow(clippy::disallowed_types, clippy::disallowed_methods)]

use sim_core::building::Building;
use sim_core::explore::{
    explore, DecisionView, Episode, EpisodeError, Event, ExploreConfig, ProgressSample, Reply,
    RobotId, RunEnd, RunResult, Strategy, StrategyParams, TeamMap,
};
use sim_core::generate::{generate, BuildingKind, GenerateConfig};

/// The nearest candidate by planned path (the first among equals): Yamauchi's rule, written
/// here from the view alone.
fn nearest(view: &DecisionView<'_>) -> Reply {
    let mut best: Option<(usize, f64)> = None;
    for c in view.candidates {
        if c.path_m.is_finite() && best.is_none_or(|(_, d)| c.path_m < d) {
            best = Some((c.id, c.path_m));
        }
    }
    match best {
        Some((id, _)) => Reply::Choose(id),
        None => Reply::Pass,
    }
}

fn nearest_config() -> ExploreConfig {
    ExploreConfig {
        strategy: Strategy::by_name("nearest", &StrategyParams::default()).unwrap(),
        ..ExploreConfig::default()
    }
}

/// Generated buildings of both kinds, with their starts, and a seed for each.
fn cases() -> Vec<(Building, u64)> {
    [
        (BuildingKind::Office, 400.0, 3, 1),
        (BuildingKind::School, 600.0, 5, 2),
    ]
    .into_iter()
    .map(|(kind, area_m2, seed, run_seed)| {
        let b = generate(&GenerateConfig {
            seed,
            area_m2,
            kind,
            ..GenerateConfig::default()
        });
        (b, run_seed)
    })
    .collect()
}

/// What a driver saw of an episode besides its result.
#[derive(Default)]
struct Seen {
    decisions_asked: usize,
    progress: Vec<ProgressSample>,
    ended: Option<RunEnd>,
}

/// Drives `episode` to its end with `step`, which advances it (here or elsewhere) and gives it
/// back with the event.
fn drive(
    mut episode: Episode,
    mut step: impl FnMut(Episode) -> (Episode, Event),
) -> (RunResult, Seen) {
    let mut seen = Seen::default();
    loop {
        let (e, event) = step(episode);
        episode = e;
        match event {
            Event::Decide(robot) => {
                let reply = nearest(&episode.view(robot).expect("a decision is pending"));
                episode.answer(robot, reply).unwrap();
                seen.decisions_asked += 1;
            }
            Event::Progress(_, s) => seen.progress.push(s),
            Event::Ended(_, end) => {
                assert!(seen.ended.is_none(), "told twice that the run ended");
                seen.ended = Some(end);
            }
            Event::Finished => return (episode.into_result().unwrap(), seen),
        }
    }
}

#[test]
fn an_episode_answered_by_a_hand_written_nearest_rule_is_the_built_in_nearest_run() {
    for (b, seed) in cases() {
        let start = b.start.unwrap();
        let built_in = explore(&b, start, &nearest_config(), seed, &mut |_| {});
        let episode = Episode::new(&b, start, nearest_config(), seed);
        let (run, seen) = drive(episode, |mut e| {
            let event = e.advance();
            (e, event)
        });
        assert!(
            run.decisions.len() >= 10,
            "{}: {}",
            b.name,
            run.decisions.len()
        );
        assert_eq!(run.decisions, built_in.decisions, "{}", b.name);
        assert_eq!(run, built_in, "{}", b.name);
        assert_eq!(run.fingerprint(), built_in.fingerprint());
        // Every decision recorded was asked (a decision may take several questions).
        assert!(seen.decisions_asked >= run.decisions.len());
        // The progress events are the result's curve; the end told as the result says.
        assert_eq!(seen.progress, run.progress, "{}", b.name);
        let ended = seen.ended.expect("the end is told");
        assert_eq!(ended.reason, run.end_reason);
        assert_eq!(ended.exploration_time_s, run.exploration_time_s);
        assert_eq!(ended.decisions, run.decisions.len());
    }
}

#[test]
fn an_episode_moved_to_another_thread_between_steps_is_the_same_run() {
    fn send_and_static<T: Send + 'static>() {}
    send_and_static::<Episode>();
    let (b, seed) = cases().remove(0);
    let start = b.start.unwrap();
    let built_in = explore(&b, start, &nearest_config(), seed, &mut |_| {});
    let episode = Episode::new(&b, start, nearest_config(), seed);
    let mut threads = 0;
    let (run, _) = drive(episode, |mut e| {
        threads += 1;
        std::thread::spawn(move || {
            let event = e.advance();
            (e, event)
        })
        .join()
        .unwrap()
    });
    assert!(threads > 100, "{threads} steps");
    assert_eq!(run, built_in);
}

#[test]
fn calls_an_episode_cannot_take_are_errors() {
    let (b, seed) = cases().remove(0);
    let start = b.start.unwrap();
    let mut episode = Episode::new(&b, start, nearest_config(), seed);
    assert_eq!(episode.robots(), vec![RobotId(0)]);
    // Nothing asked yet.
    assert!(episode.view(RobotId(0)).is_none());
    assert_eq!(
        episode.answer(RobotId(0), Reply::Pass),
        Err(EpisodeError::NotDeciding(RobotId(0)))
    );
    let robot = loop {
        if let Event::Decide(r) = episode.advance() {
            break r;
        }
    };
    // Asked: advance does not move until it is answered.
    let t = episode.time_s();
    assert_eq!(episode.advance(), Event::Decide(robot));
    assert_eq!(episode.time_s(), t);
    assert_eq!(
        episode.answer(RobotId(1), Reply::Pass),
        Err(EpisodeError::NoSuchRobot(RobotId(1), 1))
    );
    assert!(episode.view(RobotId(1)).is_none());
    // A reply naming no candidate shown is the policy's failure: the run ends at once, and the
    // policy is not told how it ended.
    let shown = episode.view(robot).unwrap().candidates.len();
    episode.answer(robot, Reply::Choose(shown + 1000)).unwrap();
    let mut events = Vec::new();
    loop {
        match episode.advance() {
            Event::Finished => break,
            e => events.push(e),
        }
    }
    assert!(
        events.iter().all(|e| matches!(e, Event::Progress(..))),
        "{events:?}"
    );
    assert_eq!(episode.advance(), Event::Finished);
    let run = episode.result().unwrap();
    assert_eq!(run.decisions.len(), 0);
    assert_eq!(run.exploration_time_s, t);
}

/// A team of two: both robots decide (each `Decide` names its robot), they never overlap, each
/// run is scored, and robot 0's run is not the run alone (the other robot is in its way and its
/// laser's), while robot 1's streams are its own. The same team is the same run again.
#[test]
fn a_team_shares_the_world_and_each_robot_is_scored() {
    let (b, seed) = cases().remove(1);
    let start = b.start.unwrap();
    let second = sim_core::geom::Pose::new(start.x_m, start.y_m, start.theta_rad + 3.0);
    // The second robot 0.6 m from the first, on free ground.
    let second = [(0.6, 0.0), (-0.6, 0.0), (0.0, 0.6), (0.0, -0.6)]
        .into_iter()
        .map(|(dx, dy)| sim_core::geom::Pose::new(start.x_m + dx, start.y_m + dy, second.theta_rad))
        .find(|p| {
            let around = [
                (0.0, 0.0),
                (0.35, 0.0),
                (-0.35, 0.0),
                (0.0, 0.35),
                (0.0, -0.35),
            ];
            around
                .iter()
                .all(|&(dx, dy)| b.is_free(p.position() + sim_core::geom::Vec2::new(dx, dy)))
        })
        .expect("a free place beside the start");
    let run_team = || {
        let mut episode = Episode::team(
            &b,
            &[start, second],
            nearest_config(),
            seed,
            None,
            TeamMap::Separate,
        );
        assert_eq!(episode.robots(), vec![RobotId(0), RobotId(1)]);
        let mut decided = [0usize; 2];
        let mut ended = [false; 2];
        let mut closest = f64::INFINITY;
        loop {
            let w = episode.world();
            let gap =
                (w.true_pose(RobotId(0)).position() - w.true_pose(RobotId(1)).position()).norm();
            closest = closest.min(gap);
            match episode.advance() {
                Event::Decide(r) => {
                    decided[r.0] += 1;
                    let reply = nearest(&episode.view(r).unwrap());
                    episode.answer(r, reply).unwrap();
                }
                Event::Ended(r, _) => ended[r.0] = true,
                Event::Progress(..) => {}
                Event::Finished => break,
            }
        }
        assert!(
            decided.iter().all(|&n| n > 3),
            "decisions per robot: {decided:?}"
        );
        assert_eq!(ended, [true, true]);
        assert!(closest >= 0.38, "the bodies came {closest} m apart");
        let results = episode.into_results();
        let results: Vec<RunResult> = results.into_iter().map(|r| r.unwrap()).collect();
        assert!(
            results.iter().all(|r| r.explored_fraction > 0.5),
            "explored"
        );
        results
    };
    let team = run_team();
    assert_eq!(team, run_team());
    let alone = explore(&b, start, &nearest_config(), seed, &mut |_| {});
    assert_ne!(team[0].trajectory, alone.trajectory);
    assert_ne!(team[0].trajectory, team[1].trajectory);
}

/// A team of no robot is an episode that is over at once, not a panic.
#[test]
fn a_team_of_no_robot_is_over_at_once() {
    let (b, seed) = cases().remove(0);
    let mut episode = Episode::team(&b, &[], nearest_config(), seed, None, TeamMap::Separate);
    assert_eq!(episode.config(), &nearest_config());
    assert!(episode.robots().is_empty());
    assert_eq!(episode.advance(), Event::Finished);
    assert!(episode.result().is_none());
    assert_eq!(
        episode.answer(RobotId(0), Reply::Pass),
        Err(EpisodeError::NoSuchRobot(RobotId(0), 0))
    );
}
