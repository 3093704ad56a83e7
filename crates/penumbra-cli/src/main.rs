//! The `penumbra` command: parse flags, load, build, render, write. The only place where errors
//! become exit codes: 0 success, 1 runtime failure, 2 invalid input or usage, 128 + the signal's
//! number when a signal stopped it (130 Ctrl-C, 143 SIGTERM, 129 SIGHUP; see `signals`).
//!
//! One module per concept: `args` (the grammar); `render`, `check`, `check_obj` and
//! `completions` (the subcommands); `aov` (`--aov` passes); `warnings` (what `check` flags);
//! `input` (the scene from a file or stdin); `cameras` (`--camera` selection); `sequence`
//! (`--frames`, `--shard`, the task list); `plan` (one checked job per task); `settings`
//! (flags over the file's settings); `output` (output names, formats, folders, stdout);
//! `task` (one job rendered and written); `record` (`--resume` and `--meta` records);
//! `poses` (`--poses`); `manifest` (`--manifest`); `summary` (what a run reports); `signals`
//! (SIGINT, SIGTERM, SIGHUP); and `failure` (exit codes and writing to stdout and stderr).

mod aov;
mod args;
mod cameras;
mod check;
mod check_gltf;
mod check_obj;
mod completions;
mod display;
mod failure;
mod input;
mod manifest;
mod output;
mod plan;
mod poses;
mod record;
mod render;
mod sequence;
mod settings;
mod signals;
mod summary;
mod task;
mod warnings;

use std::process::ExitCode;

use clap::Parser;
use penumbra::escape_controls;

use args::{Cli, Command};
use failure::note;

fn main() -> ExitCode {
    let cli = Cli::parse_from(args::with_subcommand(std::env::args_os()));
    let result = match &cli.command {
        Command::Render(args) => simd_env().and_then(|()| render::run(args)),
        Command::Check(args) => simd_env().and_then(|()| check::run(args)),
        Command::Completions { shell } => completions::run(*shell),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            if !f.message.is_empty() {
                // One message, one line: nothing from a file or path drives the terminal.
                note(&format!("error: {}", escape_controls(&f.message)));
            }
            ExitCode::from(f.code)
        }
    }
}

/// A `PENUMBRA_SIMD` that the run cannot honour (a typo, or a path this CPU lacks) is invalid
/// input, not something to ignore by picking another path.
fn simd_env() -> Result<(), failure::Failure> {
    penumbra::forced_simd_path()
        .map(|_| ())
        .map_err(failure::invalid)
}
