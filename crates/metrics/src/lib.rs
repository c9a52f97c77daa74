//! Learning-curve and gait metrics: AUC, Best-Win-50, Episodes-to-Target, track time, sway,
//! torque, power, symmetry, gait cycle and gait class — the one implementation used by the CLI
//! (`eval`, `compare`) and, through `esrl_rs`, by Python (SPEC §6; paper §5, Table 1 and Fig. 5).
//!
//! - [`CurveSummary`] and friends: AUC, nAUC, Final-50, Best-Win-50, Episodes-to-Target and
//!   the per-method target (80% of the median Best-Win-50 over the method's seeds);
//! - [`mean_sd`]: mean ± sample SD across seeds; [`iqm_interval`], [`wilson`] and
//!   [`probability_of_improvement_interval`]: the interval estimates of `rliable`;
//! - [`gait_metrics`]: behaviour of one evaluation rollout from a [`GaitTrace`], including
//!   its [`GaitCycle`] (support phases, touchdowns, alternation, cadence, step length, stride
//!   variability, the [`GaitClass`] walk/run/hop/shuffle/stand/fall) and each joint's
//!   [`JointMotion`] (range of motion, time at a limit);
//! - [`gait_phases`], [`step_lengths`], [`classify_gait`], [`joint_motion`]: the same on any
//!   contact trace or angle series, with the thresholds and their sources in
//!   [`GaitThresholds`];
//! - [`table1`], [`table1_markdown`], [`table1_csv`]: the paper's Table 1 plus gait columns;
//!   [`actuator_markdown`] and [`joint_markdown`]: per actuator torque, power, range of motion
//!   and time at a limit.
//!
//! Pure functions over plain slices and structs; this crate depends on no other esrl crate.
//!
//! ```
//! use esrl_metrics::{method_target, summarize_method, CurveSummary};
//!
//! // Two seeds of one method, 60 generations each.
//! let a: Vec<f64> = (0..60).map(|i| i as f64).collect();
//! let b: Vec<f64> = (0..60).map(|i| 2.0 * i as f64).collect();
//! let target = method_target(&[&a, &b]).unwrap(); // 0.8 × median(34.5, 69) = 41.4
//! assert!((target - 41.4).abs() < 1e-9);
//! let s: Vec<CurveSummary> = summarize_method(&[&a, &b]).unwrap();
//! assert_eq!(s[0].auc, 1770.0);
//! assert_eq!(s[0].final_50, 34.5);
//! // b's trailing mean first reaches 41.4 at index 42 (mean of 0, 2, …, 84 = 42).
//! assert_eq!(s[1].episodes_to_target, Some(42));
//! ```
//!
//! Edge cases, chosen and documented once: a curve shorter than 50 uses all its values for
//! Final-50 and Best-Win-50; the first 49 trailing means average the values available so far;
//! Episodes-to-Target is a 0-based index and `None` when never reached; the SD of one seed is
//! `None`; empty inputs and NaN/inf are errors ([`MetricsError`]), never silent NaN.
//!
//! Limitations: all metrics are computed in `f64` in one thread; curves are expected to fit in
//! memory (Best-Win-50 is O(n·50)).

mod curve;
mod cycle;
mod error;
mod gait;
mod interval;
mod motion;
mod stats;
mod table;

pub use curve::{
    auc, best_win_50, best_window_mean, episodes_to_target, episodes_to_target_window, final_50,
    final_mean, median, method_target, method_target_with, nauc, q0_mean, summarize_method,
    trailing_means, CurveSummary, TARGET_FRACTION, WINDOW,
};
pub use cycle::{
    classify_gait, gait_phases, majority_class, mean_cycle, step_lengths, GaitClass,
    GaitClassInput, GaitCycle, GaitPhases, GaitThresholds,
};
pub use error::{MetricsError, Result};
pub use gait::{gait_metrics, GaitMetrics, GaitOptions, GaitStep, GaitTrace};
pub use interval::{
    bootstrap, iqm, iqm_interval, probability_of_improvement, probability_of_improvement_interval,
    wilson, Interval, BOOTSTRAP_REPS, Z95,
};
pub use motion::{
    joint_motion, mean_joint_motion, mean_torso_pitch, percentile, pitch_of, torso_pitch,
    JointMotion, TorsoPitch,
};
pub use stats::{mean_sd, MeanSd};
pub use table::{
    actuator_markdown, format_number, gait_classes_text, joint_markdown, table1, table1_csv,
    table1_markdown, AgentRuns, Cell, SeedResult, Table1Row,
};
