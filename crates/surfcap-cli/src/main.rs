//! The `surfcap` binary: everything lives in the `surfcap_cli` library (`src/lib.rs`).

fn main() -> std::process::ExitCode {
    surfcap_cli::main()
}
