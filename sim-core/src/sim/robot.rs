//! The robot's body: a disc driven like a differential-drive base, as a rapier2d rigid body
//! among fixed walls.

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

pub(super) struct RobotBody {
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
    handle: RigidBodyHandle,
    /// Heading kept in f64 and wrapped, so that long runs do not accumulate f32 angle error.
    theta_rad: f64,
}

/// A copy of the body in its world. The physics pipeline holds only scratch buffers (rapier's
/// own note), so the copy gets a new one; a copied run is bit-identical to the original
/// (`explore::shared`'s tests).
impl Clone for RobotBody {
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
            handle: self.handle,
            theta_rad: self.theta_rad,
        }
    }
}

impl std::fmt::Debug for RobotBody {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RobotBody")
            .field("pose", &self.pose())
            .finish()
    }
}

impl RobotBody {
    pub(super) fn new(walls: &Walls, start: Pose, config: &RobotConfig) -> Self {
        let mut bodies = RigidBodySet::new();
        let mut colliders = ColliderSet::new();
        if let Some(shape) = walls.shared_shape() {
            colliders.insert(ColliderBuilder::new(shape).friction(0.0).build());
        }
        let body = RigidBodyBuilder::dynamic()
            .translation(vector![start.x_m as f32, start.y_m as f32])
            .rotation(start.theta_rad as f32)
            .gravity_scale(0.0)
            .ccd_enabled(true)
            .build();
        let handle = bodies.insert(body);
        colliders.insert_with_parent(
            ColliderBuilder::ball(config.radius_m as f32)
                .friction(0.0)
                .restitution(0.0)
                .build(),
            handle,
            &mut bodies,
        );
        Self {
            pipeline: PhysicsPipeline::new(),
            params: IntegrationParameters::default(),
            islands: IslandManager::new(),
            broad_phase: DefaultBroadPhase::new(),
            narrow_phase: NarrowPhase::new(),
            bodies,
            colliders,
            impulse_joints: ImpulseJointSet::new(),
            multibody_joints: MultibodyJointSet::new(),
            ccd: CCDSolver::new(),
            handle,
            theta_rad: start.theta_rad,
        }
    }

    pub(super) fn pose(&self) -> Pose {
        let t = self.bodies[self.handle].translation();
        Pose::new(t.x as f64, t.y as f64, self.theta_rad)
    }

    pub(super) fn step(&mut self, v_mps: f64, w_radps: f64, dt_s: f64) {
        // Integrate the heading exactly (midpoint), drive the body with the matching velocity.
        // Substeps keep contact penetration small (a few millimetres at full speed).
        let substeps = (dt_s / MAX_SUBSTEP_S).ceil().max(1.0) as usize;
        let h = dt_s / substeps as f64;
        self.params.dt = h as f32;
        for _ in 0..substeps {
            let mid = self.theta_rad + 0.5 * w_radps * h;
            let body = &mut self.bodies[self.handle];
            body.set_linvel(
                vector![(v_mps * mid.cos()) as f32, (v_mps * mid.sin()) as f32],
                true,
            );
            body.set_angvel(0.0, true);
            self.substep();
            self.theta_rad = wrap_angle(self.theta_rad + w_radps * h);
        }
        // Any velocity the contacts left over is dropped: a base stops when the command stops.
        let body = &mut self.bodies[self.handle];
        body.set_linvel(vector![0.0, 0.0], false);
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
