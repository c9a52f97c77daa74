//! The `esrl` command: parses the arguments, builds what the core crates describe, loops
//! and prints. Training is `esrl_run::Training` driving an `esrl_agents::Learner`;
//! evaluation and recording are `esrl_eval`; this crate adds the command line, progress
//! display, stop signals, the multi-run comparison and the benchmarks.

pub mod args;
pub mod bench;
pub mod compare;
pub mod eval;
pub mod record;
pub mod runs;
pub mod signals;
pub mod study;
pub mod train;

/// How a user runs this binary, for the commands messages suggest: `esrl` when the `esrl` on
/// the `PATH` is this binary, else its path relative to the working folder
/// (`target/release/esrl` after `cargo run --release` or `cargo build --release`), else its
/// absolute path.
pub fn invocation() -> String {
    let Ok(exe) = std::env::current_exe().and_then(|p| p.canonicalize()) else {
        return "esrl".into();
    };
    let on_path = std::env::var_os("PATH").is_some_and(|paths| {
        std::env::split_paths(&paths)
            .map(|d| d.join("esrl"))
            .filter_map(|p| p.canonicalize().ok())
            .next()
            .is_some_and(|p| p == exe)
    });
    if on_path {
        return "esrl".into();
    }
    let relative = std::env::current_dir()
        .ok()
        .and_then(|d| d.canonicalize().ok())
        .and_then(|d| exe.strip_prefix(d).ok().map(|r| r.to_path_buf()));
    relative.unwrap_or(exe).display().to_string()
}

/// An error and its causes on one line, `outer: inner: …`, leaving out a cause whose text
/// the line already holds (library errors often repeat their source in their own message).
pub fn error_chain(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}
