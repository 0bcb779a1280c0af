//! Random and mutated inputs give errors, never panics.
use petrel_plans::*;

#[test]
fn random_inputs_never_panic() {
    let mut seed: u64 = 12345;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 33) as usize
    };
    let alphabet: Vec<char> = "ab_c1 ;|<>?:{}()!*#\n.GOTO_LABEL_x andnot[]é$,*if**during**do*"
        .chars()
        .collect();
    let frags = [
        "a",
        "b_1",
        "|5",
        ";",
        "<",
        ">",
        "?",
        ":",
        "{",
        "}",
        "||",
        "!",
        "*if*",
        "*do*",
        "*during*",
        "(not x)",
        "LABEL_x",
        "GOTO_LABEL_x",
        "restart_action",
        "skip_action",
        "fail_plan",
        " ",
        "\n",
        "#c\n",
        "(and a",
        ")",
        "é",
    ];
    let pn = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/editor_patrol.pnml"
    ))
    .unwrap();
    for _ in 0..3000 {
        let n = rnd() % 12;
        let s: String = (0..n).map(|_| frags[rnd() % frags.len()]).collect();
        let _ = compile_text(&s, "f", "f", None);
        let _ = compile_text("a; b", "f", "f", Some((&s, "r")));
        let c: String = (0..rnd() % 15)
            .map(|_| alphabet[rnd() % alphabet.len()])
            .collect();
        let _ = parse_condition(&c);
        let _ = compile_text(&c, "f", "f", None);
        let _ = Script::parse(&c, "s");
        let mut b = pn.clone().into_bytes();
        for _ in 0..3 {
            let i = rnd() % b.len();
            b[i] = b"<>/\"= 0a[]."[rnd() % 11];
        }
        if let Ok(t) = String::from_utf8(b) {
            if let Ok(p) = parse_pnml(&t, "x", "x") {
                let _ = check(&p);
                let mut o = Vec::new();
                let _ = simulate(&p, &Script::default(), 20, &mut o);
            }
        }
        if let Ok(p) = compile_text(&s, "f", "f", None) {
            let _ = check(&p);
            let mut o = Vec::new();
            let _ = simulate(&p, &Script::default(), 20, &mut o);
        }
    }
}

#[test]
fn a_text_plan_that_is_not_utf8_is_an_error_at_its_byte_and_a_pnml_one_reads_as_latin1() {
    let dir = tempfile::tempdir().unwrap();
    let text = dir.path().join("bad.plan");
    std::fs::write(&text, b"a; b\n  c\xff; d\n").unwrap();
    let err = load_plan(&text, None).unwrap_err().to_string();
    assert!(err.contains("bad.plan:2:4"), "{err}");
    assert!(
        err.contains("expected UTF-8 text, found the byte 0xFF"),
        "{err}"
    );
    // PNML editors write ISO-8859-1: a place labelled `caf\xe9` reads as `café`.
    let pnml = dir.path().join("latin.pnml");
    let mut bytes = br#"<?xml version="1.0" encoding="ISO-8859-1"?><pnml><net id="n"><place id="p1"><name><text>caf"#.to_vec();
    bytes.extend_from_slice(b"\xe9");
    bytes.extend_from_slice(br#"</text></name><initialMarking><text>1</text></initialMarking></place><place id="p2"><name><text>goal</text></name></place><transition id="t"><name><text>[true]</text></name></transition><arc id="a1" source="p1" target="t"/><arc id="a2" source="t" target="p2"/></net></pnml>"#);
    std::fs::write(&pnml, bytes).unwrap();
    match load_plan(&pnml, None) {
        Ok(_) => {}
        Err(e) => assert!(!e.to_string().contains("UTF-8"), "{e}"),
    }
}

#[test]
fn errors_name_what_the_user_gave_a_nul_a_rules_file_a_pnml_to_compile() {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("nul.plan");
    std::fs::write(&plan, b"a; \0b\n").unwrap();
    let err = load_plan(&plan, None).unwrap_err().to_string();
    assert!(err.contains("unexpected character U+0000"), "{err}");
    std::fs::write(&plan, "a; b\n").unwrap();
    let missing = dir.path().join("missing.er");
    let err = load_plan(&plan, Some(&missing)).unwrap_err().to_string();
    assert!(err.contains("rules file"), "{err}");
    let pnml = dir.path().join("p.pnml");
    std::fs::write(&pnml, "<pnml/>").unwrap();
    let err = compile_to_pnml(&pnml, None).unwrap_err().to_string();
    assert!(err.contains("is a PNML plan already"), "{err}");
}
