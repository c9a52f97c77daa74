//! Gymnasium `Pendulum-v1`: swing a frictionless pendulum up and hold it, a fast sanity task
//! for the agents.
//!
//! Dynamics, reward and limits follow `gymnasium/envs/classic_control/pendulum.py`:
//! `θ̇' = θ̇ + (3g/(2l)·sin θ + 3/(m l²)·u)·dt`, `θ̇'` clipped to ±8, `θ' = θ + θ̇'·dt`,
//! reward `−(norm(θ)² + 0.1·θ̇² + 0.001·u²)` with `u` the clipped torque before the update,
//! g = 10, m = l = 1, dt = 0.05, |u| ≤ 2, truncation after 200 steps (the registered
//! `TimeLimit`), never terminated. Reset draws θ ∈ [−π, π], θ̇ ∈ [−1, 1] uniformly.
//! Observation `[cos θ, sin θ, θ̇]`. Action in [−1, 1], scaled to ±2 N·m.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::env::{Env, Step, StepInfo};

/// Maximum torque, N·m.
pub const MAX_TORQUE: f64 = 2.0;
/// Maximum angular speed, rad/s.
pub const MAX_SPEED: f64 = 8.0;
/// Time step, s.
pub const DT: f64 = 0.05;
/// Gravity, m/s².
pub const G: f64 = 10.0;
/// Mass, kg.
pub const M: f64 = 1.0;
/// Length, m.
pub const L: f64 = 1.0;
/// Truncation, steps.
pub const MAX_EPISODE_STEPS: usize = 200;

/// Gymnasium `Pendulum-v1`. State in f64 like Gymnasium's NumPy arrays; θ = 0 is upright.
#[derive(Clone, Debug)]
pub struct Pendulum {
    theta: f64,
    theta_dot: f64,
    steps: usize,
}

impl Default for Pendulum {
    fn default() -> Self {
        Self::new()
    }
}

/// `((x + π) mod 2π) − π` with Python's floored modulo.
pub fn angle_normalize(x: f64) -> f64 {
    (x + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI
}

impl Pendulum {
    /// A pendulum hanging still (call [`Env::reset`] before use).
    pub fn new() -> Self {
        Self {
            theta: std::f64::consts::PI,
            theta_dot: 0.0,
            steps: 0,
        }
    }

    /// The state `(θ, θ̇)`.
    pub fn state(&self) -> (f64, f64) {
        (self.theta, self.theta_dot)
    }

    /// Sets the state `(θ, θ̇)` and the step counter to 0 (for tests and demonstrations).
    pub fn set_state(&mut self, theta: f64, theta_dot: f64) {
        self.theta = theta;
        self.theta_dot = theta_dot;
        self.steps = 0;
    }

    fn obs(&self) -> Vec<f32> {
        vec![
            self.theta.cos() as f32,
            self.theta.sin() as f32,
            self.theta_dot as f32,
        ]
    }
}

impl Env for Pendulum {
    fn obs_dim(&self) -> usize {
        3
    }

    fn act_dim(&self) -> usize {
        1
    }

    fn reset(&mut self, seed: u64) -> Vec<f32> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        self.theta = rng.random_range(-std::f64::consts::PI..=std::f64::consts::PI);
        self.theta_dot = rng.random_range(-1.0..=1.0);
        self.steps = 0;
        self.obs()
    }

    fn step(&mut self, action: &[f32]) -> Step {
        let a = action.first().copied().unwrap_or(0.0);
        let a = if a.is_finite() {
            a.clamp(-1.0, 1.0)
        } else {
            0.0
        };
        let u = (a as f64 * MAX_TORQUE).clamp(-MAX_TORQUE, MAX_TORQUE);
        let th = self.theta;
        let thdot = self.theta_dot;
        let angle_cost = angle_normalize(th).powi(2);
        let speed_cost = 0.1 * thdot * thdot;
        let torque_cost = 0.001 * u * u;
        let new_thdot = (thdot + (3.0 * G / (2.0 * L) * th.sin() + 3.0 / (M * L * L) * u) * DT)
            .clamp(-MAX_SPEED, MAX_SPEED);
        self.theta = th + new_thdot * DT;
        self.theta_dot = new_thdot;
        self.steps += 1;
        let reward = -(angle_cost + speed_cost + torque_cost);
        Step {
            obs: self.obs(),
            reward: reward as f32,
            terminated: false,
            truncated: self.steps >= MAX_EPISODE_STEPS,
            info: StepInfo {
                reward_terms: vec![
                    ("angle", -angle_cost as f32),
                    ("speed", -speed_cost as f32),
                    ("torque", -torque_cost as f32),
                ],
                gait: None,
            },
        }
    }

    fn control_period(&self) -> f32 {
        DT as f32
    }

    fn max_episode_steps(&self) -> usize {
        MAX_EPISODE_STEPS
    }
}
