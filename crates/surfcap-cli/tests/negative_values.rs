//! Every numeric option takes a value that starts with a hyphen (`--opt -1`), so that a negative
//! number out of range gets the option's own range message, as `--opt=-1` does, rather than
//! clap's "unexpected argument '-1'" with a tip that does not apply. Parsing only: nothing runs.

use std::any::TypeId;

use clap::CommandFactory;
use clap::error::ErrorKind;

/// Whether the option's values parse as a number (the value parser's output type).
fn numeric(arg: &clap::Arg) -> bool {
    let t = arg.get_value_parser().type_id();
    [
        TypeId::of::<f64>(),
        TypeId::of::<f32>(),
        TypeId::of::<usize>(),
        TypeId::of::<u64>(),
        TypeId::of::<u32>(),
        TypeId::of::<u16>(),
        TypeId::of::<u8>(),
        TypeId::of::<i64>(),
        TypeId::of::<i32>(),
        TypeId::of::<surfcap_cli::options::Positive>(),
    ]
    .into_iter()
    .any(|n| t == n)
}

/// Every (subcommand path, numeric option long name) of the command tree.
fn numeric_options(cmd: &clap::Command, path: &mut Vec<String>, out: &mut Vec<(Vec<String>, String)>) {
    for a in cmd.get_arguments() {
        if let Some(long) = a.get_long()
            && a.get_action().takes_values()
            && numeric(a)
        {
            out.push((path.clone(), long.to_string()));
        }
    }
    for s in cmd.get_subcommands() {
        path.push(s.get_name().to_string());
        numeric_options(s, path, out);
        path.pop();
    }
}

fn kind(cmd: &clap::Command, path: &[String], tail: &[&str]) -> (Option<ErrorKind>, String) {
    let argv = std::iter::once("surfcap").chain(path.iter().map(String::as_str)).chain(tail.iter().copied());
    match cmd.clone().try_get_matches_from(argv) {
        Ok(_) => (None, String::new()),
        Err(e) => (Some(e.kind()), e.to_string()),
    }
}

#[test]
fn every_numeric_option_reads_a_negative_value_written_after_a_space() {
    let cmd = surfcap_cli::Cli::command();
    let mut options = Vec::new();
    numeric_options(&cmd, &mut Vec::new(), &mut options);
    assert!(options.len() > 50, "only {} numeric options found: is the type test right?", options.len());
    let mut wrong = Vec::new();
    for (path, long) in &options {
        let (spaced, said) = kind(&cmd, path, &[&format!("--{long}"), "-1"]);
        let (joined, _) = kind(&cmd, path, &[&format!("--{long}=-1")]);
        let named = spaced != Some(ErrorKind::ValueValidation) || said.contains(&format!("'--{long}"));
        if spaced == Some(ErrorKind::UnknownArgument) || spaced != joined || !named {
            wrong.push(format!("surfcap {} --{long} -1: {spaced:?} vs {joined:?}: {said}", path.join(" ")));
        }
    }
    assert!(wrong.is_empty(), "{} options refuse `--opt -1`:\n{}", wrong.len(), wrong.join("\n"));
}
