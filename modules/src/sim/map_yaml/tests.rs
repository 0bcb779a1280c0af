use super::*;

use std::path::PathBuf;

const YAML: &str = "image: w.pgm\nresolution: 0.5\norigin: [-1.0, 2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";

fn parse(text: &str) -> Result<MapYaml, String> {
    parse_map_yaml(Path::new("m.yaml"), text).map_err(|e| e.to_string())
}

#[test]
fn map_server_files_in_any_yaml_spelling() {
    let flat = parse(YAML).unwrap();
    assert_eq!(flat.image, PathBuf::from("w.pgm"));
    assert_eq!(
        (flat.resolution, flat.origin, flat.negate),
        (0.5, [-1.0, 2.0, 0.0], false)
    );
    // A block list for origin, a flow map for the whole file, quotes and `true`.
    let block = parse(&YAML.replace(
        "origin: [-1.0, 2.0, 0.0]",
        "origin:\n  - -1.0\n  - 2.0\n  - 0.0",
    ))
    .unwrap();
    assert_eq!(block, flat);
    let flow = parse("{image: \"w.pgm\", resolution: 0.5, origin: [-1, 2, 0], negate: 0, occupied_thresh: 0.65, free_thresh: 0.196, mode: trinary}")
        .unwrap();
    assert_eq!(flow, flat);
    assert!(
        parse(&YAML.replace("negate: 0", "negate: true"))
            .unwrap()
            .negate
    );
    assert_eq!(
        flat.features,
        WorldFeatures::default(),
        "no rescue keys, no features"
    );
}

#[test]
fn rescue_keys_give_victims_and_areas() {
    let text = format!(
        "{YAML}victims: [[1.0, 2.5], [3, 4]]\ndark:\n  - [0, 0, 2, 2]\nrough: [[1, 1, 3, 2], [5, 5, 6, 6]]\n"
    );
    let m = parse(&text).unwrap();
    let v: Vec<(f64, f64)> = m.features.victims.iter().map(|p| (p.0.x, p.0.y)).collect();
    assert_eq!(v, vec![(1.0, 2.5), (3.0, 4.0)]);
    assert_eq!(m.victim_positions, vec![(7, 11), (7, 23)]);
    assert_eq!(
        m.features.dark,
        vec![Rect::from_corners([0.0, 0.0, 2.0, 2.0]).unwrap()]
    );
    assert_eq!(m.features.rough.len(), 2);
}

#[test]
fn bad_values_name_file_line_column_and_expectation() {
    assert_eq!(
        parse(&YAML.replace("0.5", "-2")).unwrap_err(),
        "m.yaml:2:13: `resolution`: expected metres per pixel in 0.001..=10, got -2"
    );
    let e = parse(&YAML.replace("0.5", "big")).unwrap_err();
    assert!(e.starts_with("m.yaml:2:13: "), "{e}");
    assert_eq!(
        parse(&YAML.replace("[-1.0, 2.0, 0.0]", "[1, 2]")).unwrap_err(),
        "m.yaml:3:9: `origin`: expected `[x, y, yaw]`, got [1.0, 2.0]"
    );
    assert_eq!(
        parse(&YAML.replace("[-1.0, 2.0, 0.0]", "[1, 2, 0.5]")).unwrap_err(),
        "m.yaml:3:9: `origin`: rotated maps are not supported; expected yaw 0, got 0.5"
    );
    assert_eq!(
        parse(&YAML.replace("negate: 0", "negate: 7")).unwrap_err(),
        "m.yaml:4:9: `negate`: expected 0 or 1"
    );
    assert_eq!(
        parse(&YAML.replace("free_thresh: 0.196", "free_thresh: 0.9")).unwrap_err(),
        "m.yaml: expected free_thresh < occupied_thresh, got 0.9 >= 0.65"
    );
    assert_eq!(
        parse(&YAML.replace("negate: 0\n", "")).unwrap_err(),
        "m.yaml: missing required key `negate`"
    );
    let e = parse(&format!("{YAML}colour: red\n")).unwrap_err();
    assert!(e.starts_with("m.yaml:7:1: ") && e.contains("colour"), "{e}");
    assert_eq!(
        parse(&format!("{YAML}victims: [[1, 2], [3]]\n")).unwrap_err(),
        "m.yaml:7:19: `victims`: expected `[x, y]` in metres, got [3.0]"
    );
    let e = parse(&format!("{YAML}victims: [[1, x]]\n")).unwrap_err();
    assert!(e.starts_with("m.yaml:7:"), "{e}");
    assert_eq!(
        parse(&format!("{YAML}dark:\n  - [0, 0, 1]\n")).unwrap_err(),
        "m.yaml:8:5: `dark`: expected `[x0, y0, x1, y1]` in metres, got [0.0, 0.0, 1.0]"
    );
    assert_eq!(
        parse(&format!("{YAML}rough: [[2, 0, 1, 1]]\n")).unwrap_err(),
        "m.yaml:7:9: `rough`: expected x0 < x1 and y0 < y1 (lower-left then upper-right corner), got [2, 0, 1, 1]"
    );
    let e = parse("image: [unclosed\n").unwrap_err();
    assert!(e.starts_with("m.yaml:"), "{e}");
}

#[test]
fn deep_nesting_is_refused_not_overflowed() {
    let deep = format!(
        "{YAML}victims: {}{}\n",
        "[".repeat(100_000),
        "]".repeat(100_000)
    );
    let e = parse(&deep).unwrap_err();
    assert!(e.starts_with("m.yaml:7:"), "{e}");
    assert!(
        e.contains("nested too deeply: a map file nests lists and keys at most 16 levels"),
        "{e}"
    );
}

#[test]
fn an_origin_beyond_a_thousand_kilometres_is_refused() {
    let far = YAML.replace("origin: [-1.0, 2.0, 0.0]", "origin: [-1.0, 2e6, 0.0]");
    assert_eq!(
        parse(&far).unwrap_err(),
        "m.yaml:3:9: `origin`: expected `x, y` in metres within -1e6..=1e6 (a thousand kilometres), got -1, 2000000"
    );
}

/// The parser's size limits are said as what the file went beyond, not as the library's
/// debug form (`budget breached: Nodes { nodes: 250001 }`).
#[test]
fn a_file_beyond_the_parsers_limits_is_told_so_in_words() {
    let victims = vec!["[1, 2]"; 90_000].join(", ");
    let e = parse(&format!(
        "{YAML}victims: [{victims}]
"
    ))
    .unwrap_err();
    assert!(e.starts_with("m.yaml:7:"), "{e}");
    assert!(
        e.ends_with("the file has more than 250000 values (keys, lists and numbers), the most a map file may have"),
        "{e}"
    );
    assert!(!e.contains("budget"), "{e}");
}

#[test]
fn a_key_given_twice_is_said_in_the_map_writers_terms() {
    let e =
        parse("image: m.pgm\nresolution: 0.05\nresolution: 0.1\norigin: [0, 0, 0]\n").unwrap_err();
    assert!(e.contains("resolution: each key once"), "{e}");
    assert!(!e.contains("DuplicateKeyPolicy"), "{e}");
}
