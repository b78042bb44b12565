//! What distinguishes each team strategy (issue 81): one decision, built by hand, where the
//! strategies' rules part ways: a teammate heading for the nearest candidate, a teammate's
//! target near it, a teammate nearer to it than the deciding robot. Each row gives the
//! candidate each strategy takes.

use sim_core::explore::strategy::BuiltInPolicy;
use sim_core::explore::{
    CandidateView, DecisionView, Mate, Policy, Reply, Strategy, StrategyParams, TeamView,
};
use sim_core::geom::{Pose, Vec2};
use sim_core::grid::{Cell, Grid, GridFrame, Occupancy};

/// A candidate at `point`, `path_m` away by path, with `gain_m2`.
fn candidate(id: usize, point: Vec2, path_m: f64, gain_m2: f64) -> CandidateView {
    CandidateView {
        id,
        cell: Cell::new(0, 0),
        point,
        goal: point,
        frontier_cells: 10,
        distance_m: path_m,
        path_m,
        straight_m: path_m,
        gain_m2,
        layout_gain_m2: None,
        room: None,
    }
}

/// A teammate at `at` heading for `goal`.
fn mate(robot: usize, at: Vec2, goal: Option<Vec2>, exploring: bool) -> Mate {
    Mate {
        robot,
        pose: Pose::new(at.x, at.y, 0.0),
        goal,
        exploring,
        heard_s: 0.0,
    }
}

/// The candidate id `strategy` chooses at `view`.
fn choice(strategy: &str, view: &DecisionView<'_>) -> usize {
    let s = Strategy::by_name(strategy, &StrategyParams::default()).unwrap();
    match BuiltInPolicy::new(&s, 1).decide(view).0 {
        Reply::Choose(id) => id,
        other => panic!("{strategy}: {other:?}"),
    }
}

struct Case {
    what: &'static str,
    candidates: Vec<CandidateView>,
    mates: Vec<Mate>,
    /// Per mate, its path lengths to the candidates.
    mate_paths: Vec<Vec<f64>>,
    /// The choice of team-nearest, team-greedy, team-burgard, team-hungarian, team-minpos.
    expected: [usize; 5],
}

#[test]
fn each_team_strategy_decides_by_its_own_rule() {
    let (a, b) = (Vec2::new(2.0, 0.0), Vec2::new(-8.0, 0.0));
    let cases = [
        Case {
            what: "no teammate: the rules of one robot (nearest, the paper's utility)",
            candidates: vec![candidate(0, a, 2.0, 10.0), candidate(1, b, 8.0, 60.0)],
            mates: vec![],
            mate_paths: vec![],
            expected: [0, 1, 1, 1, 0],
        },
        Case {
            what: "a teammate heads for the nearest candidate: greedy and Burgard leave it; the assignment of least total cost sends the teammate there and the robot to the other; MinPos ranks the robot first at both",
            candidates: vec![candidate(0, a, 2.0, 10.0), candidate(1, b, 8.0, 9.0)],
            mates: vec![mate(1, Vec2::new(30.0, 0.0), Some(a), true)],
            mate_paths: vec![vec![28.0, 38.0]],
            expected: [0, 1, 1, 1, 0],
        },
        Case {
            what: "a teammate's target 1.2 m from the nearest candidate: not taken (greedy keeps it), but worth a fifth (Burgard does not)",
            candidates: vec![candidate(0, a, 2.0, 10.0), candidate(1, b, 8.0, 9.0)],
            mates: vec![mate(1, Vec2::new(30.0, 0.0), Some(a + Vec2::new(0.0, 1.2)), true)],
            mate_paths: vec![vec![28.0, 38.0]],
            expected: [0, 0, 1, 1, 0],
        },
        Case {
            what: "that teammate has ended its exploration: nobody leaves the candidate to it",
            candidates: vec![candidate(0, a, 2.0, 10.0), candidate(1, b, 8.0, 9.0)],
            mates: vec![mate(1, Vec2::new(30.0, 0.0), Some(a), false)],
            mate_paths: vec![vec![28.0, 38.0]],
            expected: [0, 0, 0, 0, 0],
        },
        Case {
            what: "a teammate a little farther from the nearest candidate and far from the other: the assignment sends the robot to the other, MinPos (rank 0 at both) to the nearest",
            candidates: vec![candidate(0, a, 2.0, 10.0), candidate(1, b, 3.0, 10.0)],
            mates: vec![mate(1, Vec2::new(4.0, 0.0), None, true)],
            mate_paths: vec![vec![2.5, 10.0]],
            expected: [0, 0, 0, 1, 0],
        },
        Case {
            what: "a teammate nearer to the nearest candidate: MinPos leaves it (rank 1) for one where the robot ranks first",
            candidates: vec![candidate(0, a, 2.0, 10.0), candidate(1, b, 3.0, 10.0)],
            mates: vec![mate(1, Vec2::new(3.0, 0.0), None, true)],
            mate_paths: vec![vec![1.0, 11.0]],
            expected: [0, 0, 0, 1, 1],
        },
    ];
    let frame = GridFrame::new(Vec2::new(-20.0, -20.0), 0.5, 80, 80);
    let map = Grid::filled(frame, Occupancy::Unknown);
    let names = [
        "team-nearest",
        "team-greedy",
        "team-burgard",
        "team-hungarian",
        "team-minpos",
    ];
    for case in &cases {
        let paths: Vec<f64> = case.mate_paths.iter().flatten().copied().collect();
        let view = DecisionView {
            decision: 0,
            attempt: 0,
            time_s: 10.0,
            pose: Pose::new(0.0, 0.0, 0.0),
            candidates: &case.candidates,
            unreachable_goal: None,
            layout: None,
            map: &map,
            between_m: None,
            team: (!case.mates.is_empty()).then_some(TeamView {
                robot: 0,
                size: case.mates.len() + 1,
                mates: &case.mates,
                mate_paths_m: Some(&paths),
            }),
        };
        let got: Vec<usize> = names.iter().map(|n| choice(n, &view)).collect();
        assert_eq!(got, case.expected, "{}", case.what);
    }
}

/// The strategies that read teammates' path lengths ask for them.
#[test]
fn the_assignments_ask_for_teammates_paths() {
    for (name, needs) in [
        ("team-nearest", false),
        ("team-greedy", false),
        ("team-burgard", false),
        ("team-hungarian", true),
        ("team-minpos", true),
    ] {
        let s = Strategy::by_name(name, &StrategyParams::default()).unwrap();
        assert_eq!(
            BuiltInPolicy::new(&s, 1).needs().mate_paths,
            needs,
            "{name}"
        );
    }
}
