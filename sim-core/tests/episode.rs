//! An [`Episode`] driven from outside, through its public interface only (issue 79): answered by
//! a hand-written nearest-frontier rule it is the built-in `nearest` run, decision for decision
//! and pose for pose; moved to another thread between steps it is the same run; calls it cannot
//! take are errors, not panics.

// Integration tests run at the edge: they spawn threads, which the kernel itself may not
// (sim-core/clippy.toml).
#![allow(clippy::disallowed_types, clippy::disallowed_methods)]

use sim_core::building::Building;
use sim_core::explore::{
    explore, DecisionView, Episode, EpisodeError, Event, ExploreConfig, ProgressSample, Reply,
    RobotId, RunEnd, RunResult, Strategy, StrategyParams,
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
            Event::Progress(s) => seen.progress.push(s),
            Event::Ended(end) => {
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
        Err(EpisodeError::NoSuchRobot(RobotId(1)))
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
        events.iter().all(|e| matches!(e, Event::Progress(_))),
        "{events:?}"
    );
    assert_eq!(episode.advance(), Event::Finished);
    let run = episode.result().unwrap();
    assert_eq!(run.decisions.len(), 0);
    assert_eq!(run.exploration_time_s, t);
}
