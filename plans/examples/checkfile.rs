//! Prints `check` and a simulation of a plan file (a development aid).
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let p = std::path::Path::new(&args[1]);
    let rules = args.get(2).map(std::path::PathBuf::from);
    let l = petrel_plans::load_plan(p, rules.as_deref()).unwrap();
    print!("{}", petrel_plans::check(&l.plan));
    let script =
        petrel_plans::Script::parse(args.get(3).map_or("", |s| s.as_str()), "arg").unwrap();
    let mut out = std::io::stdout();
    petrel_plans::simulate(&l.plan, &script, 12, &mut out).unwrap();
}
