//! The summary cards: the figures a user opens a report for, each with its
//! meaning and a link to the plot or section that shows it (issue 48). They
//! are made from the run's final `run.json`, after everything else on the
//! page ([`crate::Draft`]).

use crate::page::Card;
use serde_json::Value;

/// `x` as a percentage, one decimal.
fn pct(v: &Value) -> Option<String> {
    v.as_f64().map(|x| format!("{:.1} %", 100.0 * x))
}

/// Metres as millimetres, one decimal.
fn mm(v: &Value) -> Option<String> {
    v.as_f64().map(|x| format!("{:.1} mm", 1000.0 * x))
}

/// A count or a name as it is.
fn plain(v: &Value) -> Option<String> {
    match v {
        Value::String(s) => Some(s.clone()),
        Value::Number(n) => Some(n.to_string()),
        Value::Bool(b) => Some(b.to_string()),
        _ => None,
    }
}

/// A number of the run (`?` when absent), for the meanings.
fn num(run: &Value, key: &str) -> Option<f64> {
    crate::page::lookup(run, key).and_then(Value::as_f64)
}

/// A text of the run (`?` when absent), for the meanings.
fn text(run: &Value, key: &str) -> String {
    crate::page::lookup(run, key)
        .and_then(plain)
        .unwrap_or_else(|| "?".into())
}

/// The cards of an explore run: coverage against the coverage oracle,
/// safety, materials against the material oracle, viewpoints, robot time, wall time.
pub fn explore(run: &Value) -> Vec<Card> {
    let oracle_n = text(run, "coverage.oracle.stage_one_viewpoints");
    let oracle_a1 = num(run, "coverage.oracle.A1_after_stage_one_viewpoints")
        .map_or_else(|| "?".into(), |x| format!("{:.1} %", 100.0 * x));
    let mi = "material_identification";
    let as_many = num(run, &format!("{mi}.oracle_after_stage_two_viewpoints"))
        .map_or_else(|| "?".into(), |x| format!("{:.1} %", 100.0 * x));
    let cards = vec![
        Card::of(
            run,
            "coverage.A1",
            "A1 surfaces covered",
            pct,
            "share of the true surfaces of the structure within the arm's reach (A1) with a \
             measured point on them"
                .into(),
            Some("plot-coverage"),
        ),
        Card::of(
            run,
            "coverage.oracle.ratio_at_stage_one_end",
            "Coverage against the oracle",
            pct,
            format!(
                "Stage One's A1 over the {oracle_a1} that viewpoints chosen knowing the scene \
                 cover after as many sweeps ({oracle_n}); above 100 % beats them"
            ),
            Some("plot-coverage"),
        ),
        Card::of(
            run,
            "collisions",
            "Contacts with the structure",
            plain,
            "true contacts of any link along every motion and sweep; any but 0 is a failed run"
                .into(),
            Some("plot-view3d"),
        ),
        Card::of(
            run,
            "unsafe_configurations",
            "Unsafe configurations",
            plain,
            "executed configurations that the map of that moment did not show clear (dist(Q) ≤ 1)"
                .into(),
            Some("plot-view3d"),
        ),
        clearance(run, "plot-view3d"),
        Card::of(
            run,
            &format!("{mi}.identified"),
            "Materials identified",
            pct,
            format!(
                "share of A2's surface whose disc's most probable material has p ≥ 0.8 ({} discs)",
                text(run, &format!("{mi}.discs_identified"))
            ),
            Some("plot-materials"),
        ),
        Card::of(
            run,
            &format!("{mi}.ratio_after_stage_two_viewpoints"),
            "Materials against the oracle",
            pct,
            format!(
                "the run's identified share over the {as_many} that viewpoints chosen knowing \
                 the scene identify after as many Stage Two viewpoints ({})",
                text(run, &format!("{mi}.stage_two_viewpoints"))
            ),
            Some("plot-materials"),
        ),
        Card::of(
            run,
            &format!("{mi}.accuracy"),
            "Identified materials right",
            pct,
            "of the identified surface, the share whose most probable material is the true one"
                .into(),
            Some("materials-confusion"),
        ),
        Card::of(
            run,
            "material_accuracy",
            "Observed materials right",
            pct,
            format!(
                "of the {} discs the classifier observed, the share whose most probable \
                 material is the true one",
                text(run, "discs_observed_by_lrc")
            ),
            Some("materials-confusion"),
        ),
        Card::of(
            run,
            "viewpoints",
            "Viewpoints",
            |v| {
                let one = v.get("stage_one")?.as_u64()?;
                match v.get("stage_two").and_then(Value::as_u64) {
                    Some(two) => Some(format!("{one} + {two}")),
                    None => Some(one.to_string()),
                }
            },
            format!(
                "Stage One's and Stage Two's; Stage One ended by {}, Stage Two by {}",
                text(run, "termination"),
                text(run, "stage_two_termination")
            ),
            Some("plot-information"),
        ),
        Card::of(
            run,
            "robot_time_s.total",
            "Robot time",
            minutes,
            format!(
                "what a real arm within the scenario's joint limits would take: Stage One {} s, \
                 Stage Two {} s; moving while scanning {} s, moving {} s, standing to sweep {} s, \
                 deciding {} s",
                seconds(run, "robot_time_s.stage_one"),
                seconds(run, "robot_time_s.stage_two"),
                seconds(run, "robot_time_s.moving_while_scanning"),
                seconds(run, "robot_time_s.moving"),
                seconds(run, "robot_time_s.standing_to_sweep"),
                seconds(run, "robot_time_s.deciding")
            ),
            Some("plot-timings"),
        ),
        Card::of(
            run,
            "timings.total_s",
            "Wall time",
            |v| v.as_f64().map(|s| format!("{s:.1} s")),
            format!(
                "the whole job on this computer: Stage One {} s, Stage Two {} s, blast \
                 planning {} s",
                seconds(run, "timings.stage_one_s"),
                seconds(run, "timings.stage_two_s"),
                seconds(run, "timings.blast_planning_s")
            ),
            Some("plot-timings"),
        ),
    ];
    cards.into_iter().flatten().collect()
}

/// The smallest true clearance of the run, linked to `link`.
fn clearance(run: &Value, link: &str) -> Option<Card> {
    Card::of(
        run,
        "min_clearance_m",
        "Smallest clearance",
        mm,
        "smallest true distance between the robot and the structure over the run".into(),
        Some(link),
    )
}

/// Seconds as minutes and seconds (`38 min 30 s`).
fn minutes(v: &Value) -> Option<String> {
    let s = v.as_f64()?.round();
    Some(if s >= 60.0 {
        format!("{:.0} min {:.0} s", (s / 60.0).floor(), s % 60.0)
    } else {
        format!("{s:.0} s")
    })
}

/// Seconds of the run at `key`, one decimal.
fn seconds(run: &Value, key: &str) -> String {
    num(run, key).map_or_else(|| "?".into(), |s| format!("{s:.1}"))
}

/// The cards of a follow run: faces, edges, corners, contacts, clearance,
/// sets per m², termination, robot time, step time.
pub fn follow(run: &Value) -> Vec<Card> {
    let lambda = num(run, "score.config.lambda_m")
        .map_or_else(|| "λ".into(), |l| format!("λ = {:.0} mm", 1000.0 * l));
    let corners = crate::page::lookup(run, "score.corners")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    let cards = vec![
        Card::of(
            run,
            "score.coverage",
            "Faces modelled",
            pct,
            format!("share of the counted true faces' area with a model polygon within {lambda}"),
            Some("plot-view3d"),
        ),
        Card::of(
            run,
            "score.edge_coverage",
            "Shared edges",
            pct,
            "share of the true edges' length modelled as shared edges".into(),
            Some("plot-view3d"),
        ),
        Card::of(
            run,
            "score.corners_found",
            "Corners found",
            |v| v.as_u64().map(|n| format!("{n} of {corners}")),
            "true corners between counted faces found as corner vertices".into(),
            Some("plot-view3d"),
        ),
        Card::of(
            run,
            "collisions",
            "Contacts with the structure",
            plain,
            "steps in which any link touched the structure; any but 0 is a failed run".into(),
            Some("plot-sensing"),
        ),
        clearance(run, "plot-sensing"),
        Card::of(
            run,
            "sets_per_m2",
            "Sensor sets per m²",
            |v| v.as_f64().map(|x| format!("{x:.0}")),
            format!(
                "sensor sets over the modelled area ({} sets): the effort per square metre",
                text(run, "sets")
            ),
            Some("plot-sensing"),
        ),
        Card::of(
            run,
            "termination",
            "Ended by",
            plain,
            format!("the follower's own end, after {} steps", text(run, "steps")),
            Some("plot-modes"),
        ),
        Card::of(
            run,
            "robot_time_s.total",
            "Robot time",
            minutes,
            format!(
                "what a real arm within the joint limits would take: moving {} s, reading the \
                 sensors {} s, deciding {} s",
                seconds(run, "robot_time_s.moving"),
                seconds(run, "robot_time_s.sensing"),
                seconds(run, "robot_time_s.deciding")
            ),
            Some("plot-times"),
        ),
        Card::of(
            run,
            "step_us.mean",
            "Step time",
            |v| v.as_f64().map(|x| format!("{x:.0} µs")),
            "mean wall time of one step: model update, direction and kinematics".into(),
            Some("plot-times"),
        ),
    ];
    cards.into_iter().flatten().collect()
}
