//! `random-frontier`: a candidate drawn at random (uniformly, from the run's seed and the
//! decision), driven to until it is reached or gone (a random walk over the frontiers, each
//! goal kept as a frontier strategy keeps its goal): the floor every strategy must beat.

use super::shared::{best_of, plain, BuiltIn, NO_FRONTIER};
use crate::explore::strategy::{Choosing, Memory, Rule};

pub(super) const STRATEGY: BuiltIn = BuiltIn {
    name: "random-frontier",
    gain: "not used: a reachable candidate drawn at random from the run's seed, kept until reached or gone (the floor every strategy must beat)",
    stops: NO_FRONTIER,
    citation: "floorcast",
    settings: &[],
    make: |_| plain(RandomFrontier),
};

/// A candidate drawn at random, kept until reached or gone.
#[derive(Debug)]
struct RandomFrontier;

/// The goal drawn is kept while a candidate lies this close to the point drawn (the frontier,
/// moved a little as the map grows) and the robot is farther than this from it (m).
const RANDOM_KEEP_M: f64 = 3.0;

impl Rule for RandomFrontier {
    fn name(&self) -> &'static str {
        "random"
    }

    fn choose(&self, at: &Choosing<'_, '_>, memory: &mut Memory) -> Option<usize> {
        let (view, shown) = (at.view, at.shown);
        // The goal drawn before while it stands (a refused goal, attempt > 0, does not); else
        // a new draw.
        let robot = view.pose.position();
        let standing = memory.goal.filter(|_| view.attempt == 0).and_then(|goal| {
            best_of(shown, |c| {
                let off = (c.point - goal).norm();
                if off <= RANDOM_KEEP_M && (c.goal - robot).norm() > RANDOM_KEEP_M {
                    -off
                } else {
                    f64::NAN
                }
            })
        });
        let chosen = standing.or_else(|| {
            let draw = random_draw(memory.seed, view.decision, view.attempt);
            (!shown.is_empty()).then(|| (draw % shown.len() as u64) as usize)
        });
        memory.goal = chosen.map(|i| shown[i].point);
        chosen
    }
}

/// A number drawn from the run's seed and the decision (SplitMix64 of their mix): the same at
/// the same decision of the same run, whatever was asked before.
fn random_draw(seed: u64, decision: usize, attempt: usize) -> u64 {
    let mut z = seed
        ^ (decision as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (attempt as u64).wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}
