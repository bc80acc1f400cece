//! The `selvedge` command: see [`selvedge::cli`].

fn main() -> std::process::ExitCode {
    selvedge::cli::main()
}
