//! Foxglove-ready MCAP recordings of rollouts.
