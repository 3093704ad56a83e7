//! `penumbra completions SHELL`: the shell's completion script on stdout (clap_complete).

use clap::CommandFactory;
use clap_complete::Shell;

use crate::args::Cli;
use crate::failure::{runtime, Failure};

pub fn run(shell: Shell) -> Result<(), Failure> {
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut Cli::command(), "penumbra", &mut script);
    // Through one write, so that a closed pipe is a runtime failure, never a panic.
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_all(&script)
        .and_then(|()| out.flush())
        .map_err(|e| runtime(format!("cannot write to standard output: {e}")))
}
