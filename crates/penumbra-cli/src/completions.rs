//! `penumbra completions SHELL`: the shell's completion script on stdout (clap_complete).

use clap::CommandFactory;
use clap_complete::Shell;

use crate::args::Cli;
use crate::failure::{say, Failure};

pub fn run(shell: Shell) -> Result<(), Failure> {
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut Cli::command(), "penumbra", &mut script);
    // Through one write, so that a closed pipe ends it quietly, never with a panic.
    say(String::from_utf8_lossy(&script).trim_end())
}
