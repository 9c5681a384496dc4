//! `cargo xtask`: see the library docs. `bundle`, `bundle-universal` and `known-packages` go to
//! nice-plug's bundler (plugin bundles in `target/bundled/`, names from `bundler.toml`).

/// Commands handled by nice-plug-xtask.
const BUNDLER_COMMANDS: [&str; 3] = ["bundle", "bundle-universal", "known-packages"];

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().is_some_and(|c| BUNDLER_COMMANDS.contains(&c.as_str())) {
        if let Err(e) = nice_plug_xtask::main_with_args("cargo xtask", args) {
            eprintln!("error: {e:#}");
            std::process::exit(1);
        }
        return;
    }
    let code = xtask::run(args.into_iter().map(Into::into), &mut std::io::stdout(), &mut std::io::stderr());
    std::process::exit(code);
}
