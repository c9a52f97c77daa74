//! `esrl`: train, evaluate, compare and record humanoid walking controllers.

use clap::Parser;
use esrl::args::{Cli, Command};
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Train(args) => esrl::train::run(args).map(|_| ()),
        Command::Bench(args) => esrl::bench::run(&args.what),
        Command::Eval(args) => esrl::eval::run(args),
        Command::Compare(args) => esrl::compare::run(args),
        Command::Record(args) => esrl::record::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
