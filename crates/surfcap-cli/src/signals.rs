//! Ctrl-C and `kill` (SIGINT, SIGTERM): the temporaries of the outputs being written are removed
//! (`surfcap_mesh::temporaries`) and the previous outputs kept, then the program exits with
//! 128 + the signal's number (130, 143), as shells report a program stopped by a signal.
//! A signal that arrives while the outputs are being committed waits for the commit; when the
//! run's outputs were all committed and nothing else was in progress, the run is reported as
//! completed (exit 0), since its outputs are in place whole.
//! `signal-hook` runs the clean-up on an ordinary thread (its handler only wakes that thread),
//! so removing folders is not restricted to async-signal-safe calls.

/// Installs the handler thread (once, at start-up).
pub fn remove_temporaries_on_signals() {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGINT, SIGTERM};
        use surfcap_mesh::temporaries::{SignalOutcome, stop_for_signal};
        let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
            return;
        };
        std::thread::spawn(move || {
            if let Some(signal) = signals.forever().next() {
                match stop_for_signal() {
                    SignalOutcome::Completed(written) => {
                        let names: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
                        eprintln!(
                            "surfcap: stopped by a signal after the outputs were completed: {}",
                            names.join(", ")
                        );
                        std::process::exit(0);
                    }
                    SignalOutcome::Interrupted { completed } => {
                        if !completed.is_empty() {
                            let names: Vec<String> = completed.iter().map(|p| p.display().to_string()).collect();
                            eprintln!(
                                "surfcap: interrupted; already completed before the signal: {}",
                                names.join(", ")
                            );
                        }
                        std::process::exit(128 + signal);
                    }
                }
            }
        });
    }
}
