//! What a signal handler learns (`temporaries::signal_outcome`) before, during and after the
//! commit of an output set: its own test binary, since the outcome is process-wide.

use std::fs;

use surfcap_mesh::atomic::write_file;
use surfcap_mesh::output_set::{CommitStep, OutputSet};
use surfcap_mesh::temporaries::{SignalOutcome, signal_outcome};

#[test]
fn a_signal_after_the_commit_says_the_outputs_are_complete() {
    let d = tempfile::tempdir().unwrap();
    let glb = d.path().join("x.glb");
    let report = d.path().join("x.report.json");
    fs::write(&glb, b"old").unwrap();
    let mut set = OutputSet::new(&[]);
    set.file(&glb).unwrap();
    set.file(&report).unwrap();
    write_file(&glb, |w| w.write_all(b"new")).unwrap();
    write_file(&report, |w| w.write_all(b"{}")).unwrap();
    assert!(
        matches!(signal_outcome(), SignalOutcome::Interrupted { .. }),
        "a signal before the commit interrupts the run"
    );
    // A signal in the middle of the commit: the handler waits for it, then sees it complete.
    let mut handler = None;
    set.commit_with(&mut |step| {
        if step == CommitStep::Renamed(0) {
            // Had it not waited for the commit lock, it would see the live temporaries of the
            // outputs not yet renamed and say "interrupted".
            handler = Some(std::thread::spawn(signal_outcome));
        }
        Ok(())
    })
    .unwrap();
    let seen = handler.unwrap().join().unwrap();
    let real = fs::canonicalize(d.path()).unwrap();
    let done = vec![real.join("x.glb"), real.join("x.report.json")];
    assert_eq!(seen, SignalOutcome::Completed(done.clone()));
    assert_eq!(signal_outcome(), SignalOutcome::Completed(done));
    assert_eq!(fs::read(&glb).unwrap(), b"new");
}
