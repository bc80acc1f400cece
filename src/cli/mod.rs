//! The `selvedge` command: `run` a scene, `check` a scene, `bench` the benchmark scenes.

mod bench;
mod check;
mod run;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Exit status for a scene that cannot be used (clap uses the same for bad arguments).
const EXIT_BAD_INPUT: u8 = 2;
/// Exit status for a run that diverged.
const EXIT_DIVERGED: u8 = 3;
/// Exit status for failures to write output.
const EXIT_IO: u8 = 1;

/// Selvedge: cloth and garment simulation from RON scene files.
#[derive(Debug, Parser)]
#[command(name = "selvedge", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a scene: write frames, summary.json and probes.csv.
    Run {
        /// The scene file (RON).
        scene: PathBuf,
        /// Output folder [default: the scene's output.directory, else out/<scene name>].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Number of frames to compute, overriding the scene's duration.
        #[arg(long)]
        frames: Option<u32>,
        /// Print nothing but errors.
        #[arg(long)]
        quiet: bool,
    },
    /// Validate a scene without running it and print what it would build.
    Check {
        /// The scene file (RON).
        scene: PathBuf,
    },
    /// Time the benchmark scenes of scenes/bench/ and print a table (ms per frame is the
    /// median of the frames after a warm-up).
    Bench {
        /// Time 10 frames of each scene instead of the whole scene.
        #[arg(long)]
        quick: bool,
        /// Also write the table as JSON to this file.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Threads of the parallel loops [default: one per core].
        #[arg(long)]
        threads: Option<usize>,
        /// Only these scenes (comma-separated names, such as hang_64,sphere_64).
        #[arg(long, value_delimiter = ',')]
        only: Vec<String>,
    },
}

/// Entry point of the binary: parses arguments, runs the command, maps failures to exit
/// statuses (2 bad input, 3 diverged, 1 output failure).
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run { scene, out, frames, quiet } => run::run(&scene, out, frames, quiet),
        Command::Check { scene } => check::check(&scene),
        Command::Bench { quick, out, threads, only } => bench::bench(quick, out, threads, &only),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            eprintln!("error: {}", failure.message);
            ExitCode::from(failure.status)
        }
    }
}

/// A failed command: what to tell the user and the exit status.
struct Failure {
    message: String,
    status: u8,
}

impl Failure {
    fn bad_input(error: impl std::fmt::Display) -> Self {
        Self { message: error.to_string(), status: EXIT_BAD_INPUT }
    }

    fn io(what: impl std::fmt::Display, error: std::io::Error) -> Self {
        Self { message: format!("{what}: {error}"), status: EXIT_IO }
    }
}
