//! The `esrl` command: parses the arguments, builds what the core crates describe, loops
//! and prints. Training is `esrl_run::Training` driving an `esrl_agents::Learner`;
//! evaluation and recording are `esrl_eval`; this crate adds the command line, progress
//! display, stop signals, the multi-run comparison and the benchmarks.

pub mod args;
pub mod bench;
pub mod compare;
pub mod eval;
pub mod record;
pub mod signals;
pub mod train;

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
