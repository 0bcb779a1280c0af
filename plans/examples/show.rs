//! Prints a compiled text plan's structure (a development aid).
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rules = args.get(2).map(|r| std::fs::read_to_string(r).unwrap());
    let src = std::fs::read_to_string(&args[1]).unwrap();
    match petrel_plans::compile_text(&src, &args[1], "x", rules.as_deref().map(|r| (r, "rules"))) {
        Ok(p) => {
            for (i, pl) in p.places().iter().enumerate() {
                println!("place {i} {} '{}' {}", pl.id, pl.label, pl.initial);
            }
            for t in p.transitions() {
                let ins: Vec<_> = t
                    .inputs
                    .iter()
                    .map(|e| p.places()[e.place].label.clone())
                    .collect();
                let outs: Vec<_> = t
                    .outputs
                    .iter()
                    .map(|e| p.places()[e.place].label.clone())
                    .collect();
                println!("'{}': {} -> {}", t.label, ins.join(","), outs.join(","));
            }
        }
        Err(e) => println!("{e}"),
    }
}
