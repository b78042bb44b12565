//! The robots' bodies: discs driven like differential-drive bases, rapier2d rigid bodies among
//! fixed walls and each other, in one physics world.

use rapier2d::prelude::*;

use super::laser::Walls;
use crate::geom::{wrap_angle, Pose};

/// The robot's size and limits. Defaults: 0.2 m radius, 0.5 m/s, 1.0 rad/s (a small
/// differential-drive base such as a TurtleBot or Stage's erratic at typical navigation limits).
#[derive(Debug, Clone, PartialEq)]
pub struct RobotConfig {
    pub radius_m: f64,
    pub max_speed_mps: f64,
    pub max_turn_rate_radps: f64,
}

impl Default for RobotConfig {
    fn default() -> Self {
        Self {
            radius_m: 0.2,
            max_speed_mps: 0.5,
            max_turn_rate_radps: 1.0,
        }
    }
}

/// Longest physics substep.
const MAX_SUBSTEP_S: f64 = 0.025;

/// The physics world: the walls and every robot's body.
pub(super) struct Bodies {
    pipeline: PhysicsPipeline,
    params: IntegrationParameters,
    islands: IslandManager,
    broad_phase: DefaultBroadPhase,
    narrow_phase: NarrowPhase,
    bodies: RigidBodySet,
    colliders: ColliderSet,
    impulse_joints: ImpulseJointSet,
    multibody_joints: MultibodyJointSet,
    ccd: CCDSolver,
    /// Each robot's body and heading (kept in f64 and wrapped, so that long runs do not
    /// accumulate f32 angle error), in the order they were added.
    robots: Vec<(RigidBodyHandle, f64)>,
}

/// A copy of the bodies in their world. The physics pipeline holds only scratch buffers
/// (rapier's own note), so the copy gets a new one; a copied run is bit-identical to the
/// original (`explore::shared`'s tests).
impl Clone for Bodies {
    fn clone(&self) -> Self {
        Self {
            pipeline: PhysicsPipeline::new(),
            params: self.params,
            islands: self.islands.clone(),
            broad_phase: self.broad_phase.clone(),
            narrow_phase: self.narrow_phase.clone(),
            bodies: self.bodies.clone(),
            colliders: self.colliders.clone(),
            impulse_joints: self.impulse_joints.clone(),
            multibody_joints: self.multibody_joints.clone(),
            ccd: self.ccd.clone(),
            robots: self.robots.clone(),
        }
    }
}

impl std::fmt::Debug for Bodies {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let poses: Vec<Pose> = (0..self.robots.len()).map(|i| self.pose(i)).collect();
        f.debug_struct("Bodies").field("poses", &poses).finish()
    }
}

impl Bodies {
    /// The walls, no robot yet.
    pub(super) fn new(walls: &Walls) -> Self {
        let mut colliders = ColliderSet::new();
        if let Some(shape) = walls.shared_shape() {
            colliders.insert(ColliderBuilder::new(shape).friction(0.0).build());
        }
        Self {
            pipeline: PhysicsPipeline::new(),
            params: IntegrationParameters::default(),
            islands: IslandManager::new(),
            broad_phase: DefaultBroadPhase::new(),
            narrow_phase: NarrowPhase::new(),
            bodies: RigidBodySet::new(),
            colliders,
            impulse_joints: ImpulseJointSet::new(),
            multibody_joints: MultibodyJointSet::new(),
            ccd: CCDSolver::new(),
            robots: Vec::new(),
        }
    }

    /// A robot's disc at `start`; its index among the robots.
    pub(super) fn add(&mut self, start: Pose, config: &RobotConfig) -> usize {
        let body = RigidBodyBuilder::dynamic()
            .translation(vector![start.x_m as f32, start.y_m as f32])
            .rotation(start.theta_rad as f32)
            .gravity_scale(0.0)
            .ccd_enabled(true)
            .build();
        let handle = self.bodies.insert(body);
        self.colliders.insert_with_parent(
            ColliderBuilder::ball(config.radius_m as f32)
                .friction(0.0)
                .restitution(0.0)
                .build(),
            handle,
            &mut self.bodies,
        );
        self.robots.push((handle, start.theta_rad));
        self.robots.len() - 1
    }

    pub(super) fn pose(&self, robot: usize) -> Pose {
        let (handle, theta_rad) = self.robots[robot];
        let t = self.bodies[handle].translation();
        Pose::new(t.x as f64, t.y as f64, theta_rad)
    }

    /// Drives every robot for `dt_s` with its command `(v_mps, w_radps)` (robots without one
    /// stand still).
    pub(super) fn step(&mut self, commands: &[(f64, f64)], dt_s: f64) {
        // Integrate each heading exactly (midpoint), drive each body with the matching
        // velocity. Substeps keep contact penetration small (a few millimetres at full speed).
        let substeps = (dt_s / MAX_SUBSTEP_S).ceil().max(1.0) as usize;
        let h = dt_s / substeps as f64;
        self.params.dt = h as f32;
        let command = |i: usize| commands.get(i).copied().unwrap_or((0.0, 0.0));
        for _ in 0..substeps {
            for (i, &(handle, theta_rad)) in self.robots.iter().enumerate() {
                let (v_mps, w_radps) = command(i);
                let mid = theta_rad + 0.5 * w_radps * h;
                let body = &mut self.bodies[handle];
                body.set_linvel(
                    vector![(v_mps * mid.cos()) as f32, (v_mps * mid.sin()) as f32],
                    true,
                );
                body.set_angvel(0.0, true);
            }
            self.substep();
            for (i, (_, theta_rad)) in self.robots.iter_mut().enumerate() {
                *theta_rad = wrap_angle(*theta_rad + command(i).1 * h);
            }
        }
        // Any velocity the contacts left over is dropped: a base stops when the command stops.
        for &(handle, _) in &self.robots {
            self.bodies[handle].set_linvel(vector![0.0, 0.0], false);
        }
    }

    fn substep(&mut self) {
        self.pipeline.step(
            &vector![0.0, 0.0],
            &self.params,
            &mut self.islands,
            &mut self.broad_phase,
            &mut self.narrow_phase,
            &mut self.bodies,
            &mut self.colliders,
            &mut self.impulse_joints,
            &mut self.multibody_joints,
            &mut self.ccd,
            &(),
            &(),
        );
    }
}
