//! Learning-curve and gait metrics: AUC, Best-Win-50, Episodes-to-Target, track time, sway, torque, power, symmetry.
