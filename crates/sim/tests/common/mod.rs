//! Fixtures shared by the physics tests: the single pendulum with its hand-computable
//! constants, the two free-floating bodies of the momentum tests, and the humanoid held in
//! the air with its actuated joints as the walking task sets them up, and the humanoid held
//! in its standing pose by a stiff PD servo.
#![allow(dead_code)]

use esrl_sim::{Base, Env, PhysicsConfig, RobotModel, SimSetup, WalkConfig, WalkEnv};
use std::sync::Arc;

/// The pendulum's bob: 1.5 kg at l = 0.8 m below the pivot, with a small sphere-like
/// inertia about its centre of mass.
pub const M: f64 = 1.5;
/// Pivot to bob, m.
pub const L: f64 = 0.8;
/// The bob's inertia about its centre of mass, kg·m².
pub const I_COM: f64 = 0.004;

/// The single pendulum, hinged about y 2 m above a fixed `world` link. `joint` is the
/// hinge's URDF type (`continuous`, `revolute`), `joint_extra` URDF inside the joint
/// (`<limit …/>`, `<dynamics …/>`), and `collision` gives the bob a 5 cm sphere.
pub fn pendulum_urdf(joint: &str, joint_extra: &str, collision: bool) -> String {
    let collision = if collision {
        format!(
            "\n    <collision><origin xyz=\"0 0 -{L}\"/><geometry><sphere radius=\"0.05\"/></geometry></collision>"
        )
    } else {
        String::new()
    };
    format!(
        r#"<robot name="pendulum">
  <link name="world"/>
  <link name="bob">
    <inertial>
      <origin xyz="0 0 -{L}" rpy="0 0 0"/>
      <mass value="{M}"/>
      <inertia ixx="{I_COM}" ixy="0" ixz="0" iyy="{I_COM}" iyz="0" izz="{I_COM}"/>
    </inertial>{collision}
  </link>
  <joint name="hinge" type="{joint}">
    <origin xyz="0 0 2" rpy="0 0 0"/>
    <parent link="world"/>
    <child link="bob"/>
    <axis xyz="0 1 0"/>{joint_extra}
  </joint>
</robot>"#
    )
}

/// Two bodies joined by a hinge about y: `a` (2 kg, its centre of mass `com_a_z` above its
/// frame) and `b` (1 kg, 0.5 m below the hinge).
pub fn two_bodies_urdf(com_a_z: f64) -> String {
    format!(
        r#"<robot name="two">
      <link name="a"><inertial><origin xyz="0 0 {com_a_z}"/><mass value="2"/>
        <inertia ixx="0.2" ixy="0" ixz="0" iyy="0.3" iyz="0" izz="0.4"/></inertial></link>
      <link name="b"><inertial><origin xyz="0 0 -0.5"/><mass value="1"/>
        <inertia ixx="0.05" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.05"/></inertial></link>
      <joint name="j" type="continuous"><parent link="a"/><child link="b"/><axis xyz="0 1 0"/></joint>
    </robot>"#
    )
}

/// A floating base without gravity or ground, one solver iteration, step `dt`.
pub fn weightless(dt: f32) -> SimSetup {
    SimSetup {
        dt,
        physics: PhysicsConfig {
            gravity: 0.0,
            solver_iterations: 1,
            ..PhysicsConfig::default()
        },
        base: Base::Floating,
        ground: false,
        armature: vec![],
    }
}

/// The humanoid and `config`'s actuated joints (model indices), with the setup of the walking
/// task (its physics, substeps and actuator armature) on a fixed base without ground: the
/// torso held in the air.
pub fn held_humanoid(config: &WalkConfig) -> (Arc<RobotModel>, Vec<usize>, SimSetup) {
    let model = Arc::new(RobotModel::humanoid().unwrap());
    let actuated: Vec<usize> = config
        .actuated_joints
        .iter()
        .map(|n| model.joint_index(n).unwrap())
        .collect();
    let mut armature = vec![0.0; model.joints().len()];
    for &j in &actuated {
        armature[j] = config.physics.actuator_armature;
    }
    let setup = SimSetup {
        dt: config.control_period / config.physics.substeps as f32,
        physics: config.physics.clone(),
        base: Base::Fixed,
        ground: false,
        armature,
    };
    (model, actuated, setup)
}

/// The default walking task reset with seed 7, every actuated joint held at the standing
/// pose by a PD servo of `kp` = 2000, `kd` = 100 inside Rapier (evaluated every substep).
pub fn pd_held_standing() -> WalkEnv {
    let mut env = WalkEnv::new(WalkConfig::default()).unwrap();
    env.reset(7);
    let target = env.standing_pose();
    let joints: Vec<usize> = env
        .actuated_joint_names()
        .iter()
        .map(|n| env.model().joint_index(n).unwrap())
        .collect();
    for (k, &j) in joints.iter().enumerate() {
        env.sim_mut().set_joint_servo(j, target[k], 2000.0, 100.0);
    }
    env
}
