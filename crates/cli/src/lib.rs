//! The esrl library behind the `esrl` command: configs, run folders, checkpoints and the
//! training, evaluation, comparison, recording and benchmark drivers.

pub mod args;
pub mod bench;
pub mod checkpoint;
pub mod compare;
pub mod config;
pub mod eval;
pub mod record;
pub mod run_dir;
pub mod stick;
pub mod train;
