//! Stop requests: Ctrl-C (SIGINT) and SIGTERM, what terminals, schedulers and containers send.
//!
//! The first signal is acknowledged at once on stderr and sets a flag that every training in
//! the process polls at its generation/episode boundary: it finishes the generation or episode
//! in progress, writes a checkpoint and returns; the command then exits with the conventional
//! status 128 + the signal number (130 for SIGINT, 143 for SIGTERM). A second signal exits at
//! once with that status, losing the work since the last checkpoint.

use std::sync::atomic::{AtomicI32, Ordering};

/// The first stop signal received (0 while none).
static SIGNAL: AtomicI32 = AtomicI32::new(0);

/// The signal number of the first stop request, if one arrived.
pub fn requested() -> Option<i32> {
    match SIGNAL.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

/// The exit status of a command stopped by `signal`: 128 + its number.
pub fn exit_status(signal: i32) -> u8 {
    u8::try_from(128 + signal).unwrap_or(1)
}

fn name(signal: i32) -> &'static str {
    match signal {
        2 => "SIGINT (Ctrl-C)",
        15 => "SIGTERM",
        _ => "a stop signal",
    }
}

/// Records a stop request (what the handler does); a second one exits the process.
fn on_signal(signal: i32) {
    if SIGNAL
        .compare_exchange(0, signal, Ordering::SeqCst, Ordering::SeqCst)
        .is_ok()
    {
        eprintln!(
            "\nesrl: {} received: a training finishes the current generation/episode, writes a \
             checkpoint and exits; an evaluation reports the episodes done. Send it again to \
             quit at once (the work since the last checkpoint is lost).",
            name(signal)
        );
    } else {
        eprintln!("\nesrl: second stop signal: exiting now; resume from the last checkpoint.");
        std::process::exit(i32::from(exit_status(signal)));
    }
}

/// Installs the handlers (once per process; later calls do nothing). Failing to install only
/// loses the graceful stop, so it is reported, not fatal.
pub fn install() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        if let Err(e) = install_handlers() {
            eprintln!("esrl: cannot catch stop signals ({e}); a stop loses the work since the last checkpoint");
        }
    });
}

#[cfg(unix)]
fn install_handlers() -> std::io::Result<()> {
    use signal_hook::consts::signal::{SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])?;
    std::thread::Builder::new()
        .name("esrl-signals".into())
        .spawn(move || {
            for signal in signals.forever() {
                on_signal(signal);
            }
        })?;
    Ok(())
}

#[cfg(not(unix))]
fn install_handlers() -> std::io::Result<()> {
    ctrlc::set_handler(|| on_signal(2)).map_err(std::io::Error::other)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exit_status_is_128_plus_the_signal() {
        assert_eq!(exit_status(2), 130);
        assert_eq!(exit_status(15), 143);
    }
}
