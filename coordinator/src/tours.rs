//! The known-map tours a grid's runs need (the yardsticks of their efficiency,
//! [`floorcast_stats::yardstick`]): one per building, start pose and [`TourKey`] (six settings
//! and the grid's coverage level). `run` makes those its store lacks and stores them
//! ([`crate::store::Store::record_tour`]).

use floorcast_worker::tour::{TourKey, TourRecord};
use floorcast_worker::Settings;
use sim_core::Pose;

use crate::grid::{Plan, PlannedJob};

/// A tour a grid's runs need: its building (an index into [`Plan::buildings`]), start and the
/// settings its key is made of.
#[derive(Debug, Clone)]
pub struct PlannedTour {
    pub building: usize,
    pub start: Pose,
    pub settings: Settings,
    pub key: TourKey,
}

/// The tours `jobs` need, one per building, start and key, in the jobs' order; a job whose
/// start cannot be found (its building has none) needs none (the job fails and says why).
pub fn planned_tours(plan: &Plan, jobs: &[PlannedJob]) -> Vec<PlannedTour> {
    let mut seen = std::collections::BTreeSet::new();
    let mut out = Vec::new();
    for job in jobs {
        let building = &plan.buildings[job.building].building;
        let start = match &job.start {
            Some(g) => g.pose,
            None => match building.default_start(job.settings.robot_radius_m) {
                Ok((pose, _)) => pose,
                Err(_) => continue,
            },
        };
        let key = TourKey::of(&job.settings, plan.coverage);
        let id = (job.building, pose_bits(start), key.text());
        if seen.insert(id) {
            out.push(PlannedTour {
                building: job.building,
                start,
                settings: job.settings.clone(),
                key,
            });
        }
    }
    out
}

fn pose_bits(p: Pose) -> [u64; 3] {
    [p.x_m.to_bits(), p.y_m.to_bits(), p.theta_rad.to_bits()]
}

/// Of `planned`, those `stored` lacks.
pub fn missing<'a>(
    plan: &Plan,
    planned: &'a [PlannedTour],
    stored: &[TourRecord],
) -> Vec<&'a PlannedTour> {
    planned
        .iter()
        .filter(|t| {
            let hash = &plan.buildings[t.building].hash;
            let start = [t.start.x_m, t.start.y_m, t.start.theta_rad];
            !stored
                .iter()
                .any(|s| &s.building_hash == hash && s.starts_at(&start) && s.key == t.key)
        })
        .collect()
}
