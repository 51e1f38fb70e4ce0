//! The `surfcap-bench` binary: everything lives in the `surfcap_bench` library (`src/lib.rs`).

fn main() -> std::process::ExitCode {
    surfcap_bench::main()
}
