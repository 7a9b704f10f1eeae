mod compare;
mod render;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("compare") => compare::run(&args[1..]),
        _ => anyhow::bail!("usage: cargo xtask compare [--meshes bunny,cow,fandisk] [--no-render]"),
    }
}
