//! Teams of robots (issue 81): every team strategy explores generated buildings with 2 and 4
//! robots on a shared map, no room left, no two robots' bodies meeting, the same run for the
//! same seed; a team of one is the run alone, bit for bit.

use sim_core::building::{Building, TeamStarts};
use sim_core::explore::{
    explore, explore_team, ExploreConfig, Strategy, StrategyParams, TeamMap, TeamResult,
};
use sim_core::generate::{generate, BuildingKind, GenerateConfig};

const TEAM_STRATEGIES: [&str; 5] = [
    "team-nearest",
    "team-greedy",
    "team-burgard",
    "team-hungarian",
    "team-minpos",
];

fn config(strategy: &str) -> ExploreConfig {
    ExploreConfig {
        strategy: Strategy::by_name(strategy, &StrategyParams::default()).unwrap(),
        ..ExploreConfig::default()
    }
}

fn building(kind: BuildingKind, area_m2: f64, seed: u64) -> Building {
    generate(&GenerateConfig {
        seed,
        area_m2,
        kind,
        ..GenerateConfig::default()
    })
}

fn run(b: &Building, strategy: &str, robots: usize, seed: u64) -> TeamResult {
    let cfg = config(strategy);
    let starts = b
        .team_starts(
            b.start.unwrap(),
            robots,
            cfg.sim.robot.radius_m,
            TeamStarts::Together,
        )
        .unwrap();
    explore_team(b, &starts, &cfg, seed, TeamMap::Shared, &mut |_, _| {})
}

#[test]
fn every_team_strategy_explores_with_two_and_four_robots() {
    let b = building(BuildingKind::School, 900.0, 11);
    let radius = config("team-nearest").sim.robot.radius_m;
    for strategy in TEAM_STRATEGIES {
        for robots in [2, 4] {
            let t = run(&b, strategy, robots, 3);
            let r = &t.team;
            eprintln!(
                "{strategy} x{robots}: {:.1} % in {:.0} s ({:?}), path {:.0} m, overlap {:.0} %, min gap {:.2} m, 99 % at {:?}",
                100.0 * r.explored_fraction,
                r.exploration_time_s,
                r.end_reason,
                r.path_length_m,
                100.0 * t.overlap_fraction(),
                t.min_separation_m,
                t.time_to_fraction_s(0.99),
            );
            assert!(r.explored_fraction >= 0.99, "{strategy} x{robots}");
            assert_eq!(r.rooms_unexplored, Some(0), "{strategy} x{robots}");
            assert!(
                t.min_separation_m >= 2.0 * radius - 0.02,
                "{strategy} x{robots}"
            );
            assert_eq!(t.robots.len(), robots);
            assert!(t
                .figures
                .iter()
                .all(|f| f.path_length_m > 1.0 && f.seen_m2 > 1.0));
        }
    }
}

#[test]
fn a_team_run_is_the_same_for_the_same_seed() {
    let b = building(BuildingKind::Office, 500.0, 4);
    for strategy in ["team-hungarian", "team-minpos"] {
        let a = run(&b, strategy, 3, 7);
        assert_eq!(a, run(&b, strategy, 3, 7), "{strategy}");
        assert_eq!(a.fingerprint(), run(&b, strategy, 3, 7).fingerprint());
    }
}

#[test]
fn a_team_of_one_is_the_run_alone() {
    let b = building(BuildingKind::Office, 500.0, 4);
    for strategy in ["nearest", "baseline", "team-hungarian", "team-minpos"] {
        let alone = explore(&b, b.start.unwrap(), &config(strategy), 5, &mut |_| {});
        let team = run(&b, strategy, 1, 5);
        assert_eq!(team.robots[0], alone, "{strategy}");
        assert_eq!(team.team, alone, "{strategy}");
        assert_eq!(team.fingerprint(), alone.fingerprint());
    }
}

/// A team's starts: robot 0 where given, the others 2 radii + 0.3 m apart at least, each with
/// room for its body; together around robot 0 with its heading, or drawn: the same for the
/// same seed and index, elsewhere for another index.
#[test]
fn team_starts_keep_their_distance_and_are_reproducible() {
    let b = building(BuildingKind::Office, 800.0, 6);
    let radius = config("team-nearest").sim.robot.radius_m;
    let first = b.start.unwrap();
    let spacing = 2.0 * radius + sim_core::building::TEAM_SPACING_EXTRA_M;
    for rule in [
        TeamStarts::Together,
        TeamStarts::Random { seed: 3, index: 0 },
        TeamStarts::Random { seed: 3, index: 7 },
    ] {
        let starts = b.team_starts(first, 6, radius, rule).unwrap();
        assert_eq!(starts.len(), 6);
        assert_eq!(starts[0], first);
        for (i, p) in starts.iter().enumerate() {
            assert!(b.check_start(*p, radius).is_ok(), "{rule:?}: robot {i}");
            for q in &starts[..i] {
                assert!(
                    (p.position() - q.position()).norm() >= spacing - 1e-9,
                    "{rule:?}"
                );
            }
            if rule == TeamStarts::Together {
                assert_eq!(p.theta_rad, first.theta_rad);
            }
        }
        assert_eq!(starts, b.team_starts(first, 6, radius, rule).unwrap());
    }
    let drawn = |index| {
        b.team_starts(first, 3, radius, TeamStarts::Random { seed: 3, index })
            .unwrap()
    };
    assert_ne!(drawn(0)[1], drawn(7)[1]);
    // Eight robots of 1 m radius do not fit around the start of a small office: an error
    // naming how many did, not a panic.
    let tiny = building(BuildingKind::Office, 60.0, 1);
    let many = tiny.team_starts(tiny.start.unwrap(), 8, 1.0, TeamStarts::Together);
    assert!(
        matches!(
            many,
            Err(sim_core::building::StartError::NoRoomForTeam { robots: 8, placed }) if placed < 8
        ),
        "{many:?}"
    );
}
