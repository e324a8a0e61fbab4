//! The `hyst` command-line program: parse the arguments, run one command, say its error.
//!
//! Each subcommand's arguments and its run live in `cmd/` (one module per subcommand).

use std::process::ExitCode;

use clap::Parser;

mod cmd;

use cmd::{Cli, Command};

fn main() -> ExitCode {
    let cli = Cli::parse();
    cmd::set_read_options(&cli);
    let result = cmd::check_output_folders(&cli.command).and_then(|()| match &cli.command {
        Command::Simulate(a) => cmd::simulate::run(a),
        Command::Excite(a) => cmd::simulate::excite(a),
        Command::Ssi(a) => cmd::ssi::run(a),
        Command::Ident(a) => cmd::ident::run(a),
        Command::Refine(a) => cmd::refine::run(a),
        Command::Levels(a) => cmd::levels::run(a),
        Command::Amplitude(a) => cmd::amplitude::run(a),
        Command::Frf(a) => cmd::frf::run(a),
        Command::Track(a) if a.follow => cmd::follow::run(a),
        Command::Track(a) => cmd::track::run(a),
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
