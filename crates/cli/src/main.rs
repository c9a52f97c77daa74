//! `esrl`: train, evaluate, compare and record humanoid walking controllers.

use clap::Parser;
use esrl::args::{Cli, Command};
use std::process::ExitCode;

fn main() -> ExitCode {
    esrl_run::set_command(esrl::invocation());
    let cli = Cli::parse();
    // Every thread that computes runs with subnormal floats flushed to zero
    // (`esrl_nn::subnormal`): this one, rayon's global pool and the pools the commands build.
    esrl_nn::subnormal::init_global_pool();
    let result = esrl_nn::subnormal::flushing(|| match &cli.command {
        Command::Train(args) => esrl::train::run(args).map(|_| ()),
        Command::Bench(args) => esrl::bench::run(&args.what),
        Command::Eval(args) => esrl::eval::run(args),
        Command::Compare(args) => esrl::compare::run(args),
        Command::Record(args) => esrl::record::run(args),
        Command::Study(args) => esrl::study::run(args),
    });
    // A stop signal ends a command with the conventional status once its checkpoint is
    // written, whether the command then returned normally or with the error saying so.
    let stopped = esrl::signals::requested().map(esrl::signals::exit_status);
    match (result, stopped) {
        (Ok(()), None) => ExitCode::SUCCESS,
        (Ok(()), Some(status)) => ExitCode::from(status),
        (Err(e), stopped) => {
            eprintln!("error: {}", esrl::error_chain(&e));
            stopped.map_or(ExitCode::FAILURE, ExitCode::from)
        }
    }
}
