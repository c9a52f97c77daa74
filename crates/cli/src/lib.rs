//! The esrl library behind the `esrl` command: configs, run folders, training drivers.
