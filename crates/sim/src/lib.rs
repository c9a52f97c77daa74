//! Rapier multibody humanoid built from URDF, the walking environment and a pendulum sanity task.
//!
//! TODO-DOCS
#![forbid(unsafe_code)]

pub mod bench;
mod env;
mod error;
mod math;
mod model;
pub mod pendulum;
mod sim;
pub mod walk;

pub use env::{Env, GaitSample, Step, StepInfo};
pub use error::{SimError, UrdfError};
pub use model::{
    JointKind, JointModel, LinkGeometry, LinkModel, LinkPose, RobotModel, Shape, ShapeGeometry,
    HUMANOID_URDF,
};
pub use pendulum::Pendulum;
pub use sim::{Base, PhysicsConfig, RobotSim, RobotState, SimSetup};
pub use walk::{FallConfig, InitNoise, ObsLayout, RewardConfig, WalkConfig, WalkEnv};
