//! Ctrl-C and `kill` (SIGINT, SIGTERM): the temporaries of the outputs being written are removed
//! (`surfcap_mesh::temporaries`) and the previous outputs kept, then the program exits with
//! 128 + the signal's number (130, 143), as shells report a program stopped by a signal.
//! `signal-hook` runs the clean-up on an ordinary thread (its handler only wakes that thread),
//! so removing folders is not restricted to async-signal-safe calls.

/// Installs the handler thread (once, at start-up).
pub fn remove_temporaries_on_signals() {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGINT, SIGTERM};
        let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
            return;
        };
        std::thread::spawn(move || {
            if let Some(signal) = signals.forever().next() {
                surfcap_mesh::temporaries::remove_live();
                std::process::exit(128 + signal);
            }
        });
    }
}
