//! Contract: a free body dropped above the ground follows `z = z₀ − ½ g t²` until contact,
//! then rests on the ground carrying its weight.
//!
//! Rapier integrates with symplectic Euler at the solver substep `h = dt / solver_iterations`:
//! the velocity `g t` is exact at every step and the drop is `½ g t (t + h)`, i.e. 1 % above
//! `½ g t²` at `t = 100 h`. The test checks the velocity within 1 % at every control step, the
//! drop within 1 % of `½ g t²` after `t = 100 h`, and the drop against the discrete formula
//! within 0.1 % throughout, all at the default physics step.

use std::sync::Arc;

use esrl_sim::{Base, PhysicsConfig, RobotModel, RobotSim, RobotState, SimSetup};

const BOX: &str = r#"<robot name="box">
  <link name="box">
    <inertial><mass value="3"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
    <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
  </link>
</robot>"#;

#[test]
fn free_fall_then_rest() {
    let physics = PhysicsConfig::default();
    let g = physics.gravity as f64;
    let h = 0.025 / (physics.substeps * physics.solver_iterations) as f64;
    let setup = SimSetup {
        dt: 0.025 / physics.substeps as f32,
        physics,
        base: Base::Floating,
        ground: true,
        armature: vec![],
    };
    let z0 = 5.0;
    let model = Arc::new(RobotModel::from_urdf_str(BOX).unwrap());
    let state = RobotState {
        base_position: [0.0, 0.0, z0],
        q: vec![],
        qd: vec![],
    };
    let mut sim = RobotSim::new(model, &setup, &state).unwrap();
    let mut checked = 0;
    // Contact starts when the bottom face (0.1 m below the centre) reaches the ground.
    loop {
        sim.step();
        let t = sim.time();
        let z = sim.link_pose(0).translation.z as f64;
        if z - 0.1 < 0.05 {
            break;
        }
        let drop = z0 - z;
        let v = -sim.link_velocity(0).0.z as f64;
        assert!(
            (v / (g * t) - 1.0).abs() < 0.01,
            "t = {t}: v = {v} vs g t = {}",
            g * t
        );
        let discrete = 0.5 * g * t * (t + h);
        assert!(
            (drop / discrete - 1.0).abs() < 1e-3,
            "t = {t}: drop {drop} vs {discrete}"
        );
        if t > 100.5 * h {
            let exact = 0.5 * g * t * t;
            assert!(
                (drop / exact - 1.0).abs() < 0.01,
                "t = {t}: drop {drop} vs ½gt² = {exact}"
            );
            checked += 1;
        }
        assert_eq!(
            sim.ground_normal_force(0),
            0.0,
            "contact force before contact at t = {t}"
        );
    }
    assert!(checked > 5, "only {checked} steps checked against ½gt²");
    // Let it settle, then the ground carries the weight.
    for _ in 0..120 {
        sim.step();
    }
    let z = sim.link_pose(0).translation.z as f64;
    assert!((z - 0.1).abs() < 0.01, "rest height {z}");
    let weight = 3.0 * g;
    let f = sim.ground_normal_force(0) as f64;
    assert!(
        (f / weight - 1.0).abs() < 0.01,
        "normal force {f} N vs weight {weight} N"
    );
}
