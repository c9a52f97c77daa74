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
pub mod signals;
pub mod stick;
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
