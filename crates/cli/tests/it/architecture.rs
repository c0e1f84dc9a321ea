//! Issue 23 acceptance 1: the dependency graph `cargo metadata` reports
//! keeps the layout of SPEC §1. Every workspace crate stands on a floor and
//! uses only crates on lower floors (the floors are the diagram in the
//! README's "Architecture" section, which this test reads, and SPEC §1's
//! when `../shared/SPEC.md` is at hand); `report` depends on none of `sim`,
//! `explore`, `plan`, `map`; `explore` and `follow` depend on `hw`, not on
//! `sim`; nothing depends on `cli`; and each crate README's "May depend on"
//! paragraph names exactly the workspace crates its manifest does.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Per workspace crate: its normal and its dev dependencies on workspace crates.
type Graph = BTreeMap<String, (BTreeSet<String>, BTreeSet<String>)>;

fn metadata() -> Graph {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(root())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let packages = v["packages"].as_array().unwrap();
    let names: BTreeSet<String> = packages
        .iter()
        .map(|p| p["name"].as_str().unwrap().to_owned())
        .collect();
    packages
        .iter()
        .map(|p| {
            let (mut normal, mut dev) = (BTreeSet::new(), BTreeSet::new());
            for d in p["dependencies"].as_array().unwrap() {
                let name = d["name"].as_str().unwrap().to_owned();
                if !names.contains(&name) {
                    continue;
                }
                match d["kind"].as_str() {
                    Some("dev") => dev.insert(name),
                    _ => normal.insert(name),
                };
            }
            (p["name"].as_str().unwrap().to_owned(), (normal, dev))
        })
        .collect()
}

/// The floors of a diagram of lines `floor N   a, b, c   what ...`.
fn floors(text: &str) -> BTreeMap<String, u32> {
    let mut out = BTreeMap::new();
    for line in text.lines() {
        let Some(rest) = line.trim_start().strip_prefix("floor ") else {
            continue;
        };
        let mut words = rest.split_whitespace();
        let Some(Ok(n)) = words.next().map(str::parse::<u32>) else {
            continue;
        };
        // The crate names: comma-separated words up to the first one
        // without a trailing comma.
        for w in words {
            let name = w.trim_end_matches(',');
            out.insert(name.to_owned(), n);
            if !w.ends_with(',') {
                break;
            }
        }
    }
    out
}

fn readme_floors() -> BTreeMap<String, u32> {
    let text = std::fs::read_to_string(root().join("README.md")).unwrap();
    let f = floors(&text);
    assert!(f.len() >= 15, "README.md: no floor diagram found: {f:?}");
    f
}

#[test]
fn every_crate_uses_only_crates_on_lower_floors() {
    let graph = metadata();
    let floor = readme_floors();
    for (name, (normal, dev)) in &graph {
        let Some(&mine) = floor.get(name) else {
            // Test-only crates stand outside the floors: nothing may use
            // them but as a dev-dependency.
            for (other, (n, _)) in &graph {
                assert!(!n.contains(name), "{other} depends on the test-only {name}");
            }
            continue;
        };
        for d in normal {
            let theirs = floor.get(d).copied();
            assert!(
                theirs.is_some_and(|t| t < mine),
                "{name} (floor {mine}) depends on {d} (floor {theirs:?}): dependencies point down"
            );
        }
        for d in dev {
            assert_ne!(d, "cli", "{name} depends on cli");
        }
    }
    // Every floor crate of the diagram that exists is a workspace crate
    // (the Python and ROS 2 crates come with their issues).
    for name in floor.keys() {
        assert!(
            graph.contains_key(name) || ["py", "ros2"].contains(&name.as_str()),
            "the diagram names {name}, which the workspace lacks"
        );
    }
}

#[test]
fn the_readme_diagram_is_spec_section_1() {
    let spec = root().join("../shared/SPEC.md");
    let Ok(text) = std::fs::read_to_string(&spec) else {
        eprintln!(
            "{} is not here: only the README's diagram is checked",
            spec.display()
        );
        return;
    };
    assert_eq!(
        floors(&text),
        readme_floors(),
        "README.md against {}",
        spec.display()
    );
}

#[test]
fn the_rules_of_issue_23_hold() {
    let graph = metadata();
    let normal = |c: &str| &graph[c].0;
    for banned in ["sim", "explore", "plan", "map"] {
        assert!(
            !normal("report").contains(banned),
            "report depends on {banned}"
        );
    }
    for l in ["explore", "follow"] {
        assert!(normal(l).contains("hw"), "{l} does not depend on hw");
        assert!(!normal(l).contains("sim"), "{l} depends on sim");
    }
    for (name, (n, d)) in &graph {
        assert!(
            !n.contains("cli") && !d.contains("cli"),
            "{name} depends on cli"
        );
    }
}

#[test]
fn each_crate_readme_names_its_dependencies() {
    let graph = metadata();
    for (name, (normal, _)) in &graph {
        let path = root().join("crates").join(name).join("README.md");
        let text = std::fs::read_to_string(&path).unwrap();
        let Some(start) = text.find("**May depend on") else {
            panic!("{}: no \"May depend on\" paragraph", path.display());
        };
        let para = text[start..].split("\n\n").next().unwrap_or_default();
        // The workspace crates it names, in backticks, before "External".
        let inside = para.split("External").next().unwrap_or_default();
        let named: BTreeSet<String> = inside
            .split('`')
            .skip(1)
            .step_by(2)
            .filter(|w| graph.contains_key(*w))
            .map(str::to_owned)
            .collect();
        assert_eq!(
            &named,
            normal,
            "{}: the README's \"May depend on\" names {named:?}, the manifest {normal:?}",
            path.display()
        );
    }
}

/// `src` without its `//` comments (line and doc comments): what names
/// items.
fn code_of(src: &str) -> String {
    src.lines()
        .map(|l| l.split("//").next().unwrap_or_default())
        .collect::<Vec<_>>()
        .join("\n")
}

/// The paths into crate `krate` that `code` names (`krate::…` not preceded
/// by an identifier character or `::`), one entry per occurrence.
fn paths_into(code: &str, krate: &str) -> Vec<String> {
    let needle = format!("{krate}::");
    let mut out = Vec::new();
    for (i, _) in code.match_indices(&needle) {
        let before = code[..i].chars().next_back();
        let free = before.is_none_or(|c| !(c.is_alphanumeric() || c == '_' || c == ':'));
        if free {
            let end = code[i..]
                .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .map_or(code.len(), |e| i + e);
            out.push(code[i..end].to_owned());
        }
    }
    out
}

#[test]
fn paths_into_finds_a_crate_path_and_nothing_else() {
    let code = code_of(
        "use sim::SimRig; // sim::not_this\nlet x = ros2::sim::y; let z = oursim::q; sim::explore_job::f();",
    );
    assert_eq!(
        paths_into(&code, "sim"),
        ["sim::SimRig", "sim::explore_job::f"]
    );
}

/// Issue 46 acceptance 6: a robot's run is not the simulator's. The
/// `--ros2` paths of the binary (`commands/on_robot.rs`: the connection,
/// the live view, the exploration and the surface following on a ROS 2
/// robot) name no `sim` item: the jobs they run are `scenario::job`'s. `py` has no ROS 2 path (it does
/// not depend on `ros2`); if it gains one, this test is where to check it.
#[test]
fn the_ros2_paths_use_no_sim_type() {
    let path = root().join("crates/cli/src/commands/on_robot.rs");
    let code = code_of(&std::fs::read_to_string(&path).unwrap());
    for job in ["HardwareExplore", "HardwareFollow"] {
        assert!(code.contains(job), "{}: {job} moved?", path.display());
    }
    let named = paths_into(&code, "sim");
    assert!(
        named.is_empty() && !code.contains("use sim"),
        "{} names simulator items: {named:?}",
        path.display()
    );
    let graph = metadata();
    assert!(
        !graph["py"].0.contains("ros2"),
        "py now depends on ros2: check its ROS 2 path as the binary's is checked here"
    );
    // The job a robot runs lives below the simulator.
    for krate in ["scenario", "explore", "ros2"] {
        assert!(!graph[krate].0.contains("sim"), "{krate} depends on sim");
    }
}
