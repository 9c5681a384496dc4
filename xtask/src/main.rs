//! `cargo xtask`: the command line of the library ([`xtask::Cli`]); `cargo xtask --help` lists
//! the tasks and `cargo xtask TASK --help` explains one.

fn main() {
    let code = xtask::run(std::env::args_os().skip(1), &mut std::io::stdout(), &mut std::io::stderr());
    std::process::exit(code);
}
