//! Command-line behaviour: exit codes, messages that name the problem and the fix, reports that
//! match their schema, and a case file the code has never seen.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use hgym::flow::Level;

fn hgym(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hgym")).args(args).output().expect("run hgym")
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// The JSON `hgym args` prints, after asserting that it succeeded.
fn json_of(args: &[&str]) -> serde_json::Value {
    let o = hgym(args);
    let (out, err) = text(&o);
    assert!(o.status.success(), "hgym {}: {err}", args.join(" "));
    serde_json::from_str(&out).expect("JSON")
}

mod common;
use common::repo;

fn write_case(dir: &Path, name: &str, body: &str) -> PathBuf {
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, body).unwrap();
    p
}

/// A small, fast cylinder case: the bundled Re 100 case without its absorbing layers (the last
/// tables of the file; tests that need layers add their own), with `edit`'s replacements applied.
fn small_case(edit: &[(&str, &str)]) -> String {
    let mut s = std::fs::read_to_string(repo().join("benchmarks/validation/cylinder_re100.toml")).unwrap();
    if let Some(i) = s.find("\n[[sponge]]") {
        let layer_keys = ["[[sponge]]", "edge =", "thickness =", "strength ="];
        let tail_is_layers = s[i..]
            .lines()
            .all(|l| l.trim().is_empty() || layer_keys.iter().any(|k| l.starts_with(k)));
        assert!(tail_is_layers, "the template has tables after its [[sponge]] layers");
        s.truncate(i + 1);
    }
    for (from, to) in edit {
        assert!(s.contains(from), "template has no '{from}'");
        s = s.replace(from, to);
    }
    s
}

fn schema_check(json: &serde_json::Value) {
    let schema: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(repo().join("schemas/validation.schema.json")).unwrap()).unwrap();
    let validator = jsonschema::validator_for(&schema).expect("schema compiles");
    let errors: Vec<String> = validator.iter_errors(json).map(|e| format!("{e} at {}", e.instance_path)).collect();
    assert!(
        errors.is_empty(),
        "report does not match schemas/validation.schema.json: {errors:?}"
    );
}

#[test]
fn help_explains_the_commands() {
    let o = hgym(&["--help"]);
    assert!(o.status.success());
    let (out, _) = text(&o);
    assert!(out.contains("validate") && out.contains("bench"));
    let o = hgym(&["validate", "--help"]);
    assert!(o.status.success());
    assert!(text(&o).0.contains("--case"));
}

#[test]
fn no_arguments_is_a_usage_error() {
    assert_eq!(hgym(&[]).status.code(), Some(2));
    let o = hgym(&["validate"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).1.contains("cylinder"), "should list the families: {}", text(&o).1);
}

#[test]
fn list_shows_the_bundled_cases() {
    let o = hgym(&["validate", "--list"]);
    assert!(o.status.success());
    let (out, _) = text(&o);
    assert!(out.contains("cylinder_re100") && out.contains("cylinder_re200"));
    assert!(out.contains("kolmogorov_re40") && out.contains("channel_retau180"), "{out}");
}

#[test]
fn unknown_family_exits_2_with_the_list() {
    let o = hgym(&["validate", "cylindre"]);
    assert_eq!(o.status.code(), Some(2));
    let (_, err) = text(&o);
    assert!(
        err.contains("unknown validation family or case 'cylindre'") && err.contains("cylinder"),
        "{err}"
    );
}

#[test]
fn missing_case_file_exits_2() {
    let o = hgym(&["validate", "--case", "/nonexistent/case.toml"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).1.contains("/nonexistent/case.toml"));
}

#[test]
fn malformed_toml_exits_2_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_case(dir.path(), "broken", "[case\nname = 1");
    let o = hgym(&["validate", "--case", p.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let (_, err) = text(&o);
    assert!(err.contains("malformed case file") && err.contains("broken.toml"), "{err}");
}

#[test]
fn unknown_key_exits_2_naming_the_key_and_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_case(
        dir.path(),
        "typo",
        &small_case(&[("reynolds = 100.0", "reynolds = 100.0\nviscosity = 0.01")]),
    );
    let o = hgym(&["validate", "--case", p.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let (_, err) = text(&o);
    assert!(err.contains("viscosity") && err.contains("typo.toml"), "{err}");
}

#[test]
fn tau_too_close_to_one_half_is_refused_with_a_suggestion() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_case(dir.path(), "lowtau", &small_case(&[("reynolds = 100.0", "reynolds = 100000.0")]));
    let o = hgym(&["validate", "--case", p.to_str().unwrap(), "--level", "coarse"]);
    assert_eq!(o.status.code(), Some(2));
    let (_, err) = text(&o);
    assert!(
        err.contains("tau") && err.contains("too close to 1/2") && err.contains("cells per length"),
        "{err}"
    );
}

#[test]
fn mach_too_high_is_refused_with_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_case(
        dir.path(),
        "fast",
        &small_case(&[("lattice_velocity = 0.05", "lattice_velocity = 0.3")]),
    );
    let o = hgym(&["validate", "--case", p.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let (_, err) = text(&o);
    assert!(err.contains("Mach") && err.contains("lower lattice_velocity"), "{err}");
}

#[test]
fn body_larger_than_the_domain_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_case(dir.path(), "big", &small_case(&[("diameter = 1.0", "diameter = 45.0")]));
    let o = hgym(&["validate", "--case", p.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let (_, err) = text(&o);
    assert!(
        err.contains("does not fit inside the domain") && err.contains("enlarge the domain"),
        "{err}"
    );
}

/// `hgym validate --case CASE --level coarse --out OUT` (with `--json` when asked).
fn run_coarse(case: &Path, out: &Path, json: bool) -> std::process::Output {
    let mut args = vec![
        "validate",
        "--case",
        case.to_str().unwrap(),
        "--level",
        "coarse",
        "--out",
        out.to_str().unwrap(),
    ];
    if json {
        args.push("--json");
    }
    hgym(&args)
}

/// Writes `body` as case `name` in `dir` and runs it at the coarse level: it must be refused
/// before anything runs (exit 2). Returns the error output.
fn refused(dir: &Path, name: &str, body: &str) -> String {
    let case = write_case(dir, name, body);
    let o = run_coarse(&case, &dir.join(format!("{name}_out")), false);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{name}: {err}");
    err
}

/// Runs one case file at the coarse level into `out`; it must pass. Returns its JSON report.
fn validate_coarse(case: &Path, out: &Path) -> serde_json::Value {
    let o = run_coarse(case, out, true);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(0), "stdout: {stdout}\nstderr: {stderr}");
    let reports: serde_json::Value = serde_json::from_str(&stdout).expect("stdout is JSON");
    assert_eq!(reports.as_array().map(Vec::len), Some(1), "one report per case");
    reports[0].clone()
}

/// The measured value of quantity `q` in a report.
fn measured(report: &serde_json::Value, q: &str) -> f64 {
    let quantity = report["quantities"].as_array().unwrap().iter().find(|x| x["name"] == q);
    quantity.unwrap_or_else(|| panic!("no {q} in the report"))["measured"]
        .as_f64()
        .unwrap()
}

/// `[[sponge]]` tables for `edges`, `thickness` L thick.
fn sponges(edges: &[&str], thickness: f64) -> String {
    edges
        .iter()
        .map(|e| format!("[[sponge]]\nedge = \"{e}\"\nthickness = {thickness}\nstrength = 0.05\n\n"))
        .collect()
}

/// Hostile case files (issue 36): sizes that would wrap or allocate terabytes, numbers that are
/// not numbers, bodies that vanish, arrays with a third element, windows of no step, names that
/// fail only at the end, a case with nothing to judge. Each is refused before anything runs
/// (exit 2), naming the field.
#[test]
fn hostile_case_files_are_refused_before_running_naming_the_field() {
    let tmp = tempfile::tempdir().unwrap();
    let extra_body = |d: &str| format!("[[more_bodies]]\nshape = \"circle\"\ncenter = [30.0, 0.0]\ndiameter = {d}\n\n[domain]");
    let long_name = format!("name = \"{}\"", "a".repeat(300));
    let no_refs = {
        let s = small_case(&[]);
        s[..s.find("[[reference]]").unwrap()].to_string()
    };
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "tiny_diameter",
            small_case(&[("diameter = 1.0", "diameter = 1e-300")]),
            "GB of populations",
        ),
        (
            "huge_domain",
            small_case(&[("x = [0.0, 60.0]", "x = [0.0, 1e300]")]),
            "GB of populations",
        ),
        (
            "wrapping_domain",
            small_case(&[("x = [0.0, 60.0]", "x = [0.0, 4294967296.0]")]),
            "limit is 50000000",
        ),
        ("huge_spin_up", small_case(&[("spin_up = 50.0", "spin_up = 1e300")]), "`time`"),
        ("huge_average", small_case(&[("average = 40.0", "average = 1e9")]), "`time`"),
        (
            "long_run",
            small_case(&[("average = 40.0", "average = 9e4"), ("coarse = 12", "coarse = 100")]),
            "lattice steps",
        ),
        ("empty_window", small_case(&[("average = 40.0", "average = 1e-9")]), "at least 100"),
        (
            "three_numbers",
            small_case(&[("x = [0.0, 60.0]", "x = [0.0, 60.0, 90.0]")]),
            "expected two numbers",
        ),
        ("zero_body", small_case(&[("[domain]", &extra_body("0.0"))]), "body 2: diameter"),
        ("nan_body", small_case(&[("[domain]", &extra_body("nan"))]), "body 2: diameter"),
        (
            "nan_center",
            small_case(&[("center = [20.0, 0.0]", "center = [nan, 0.0]")]),
            "body 1: center",
        ),
        ("nan_reference", small_case(&[("value = 0.165", "value = nan")]), "reference.value"),
        ("inf_reference", small_case(&[("value = 0.165", "value = inf")]), "reference.value"),
        ("zero_reference", small_case(&[("value = 0.165", "value = 0.0")]), "reference.value"),
        ("long_name", small_case(&[("name = \"cylinder_re100\"", &long_name)]), "case.name"),
    ];
    for (name, body, words) in &cases {
        let t0 = std::time::Instant::now();
        let err = refused(tmp.path(), name, body);
        assert!(err.contains(words), "{name}: {err}");
        assert!(!err.contains("panicked") && err.len() < 2000, "{name}: {err}");
        assert!(t0.elapsed().as_secs() < 10, "{name}: refused before running");
    }
    // Nothing to judge: measured, reported as UNJUDGED, never as PASS.
    let no_refs = no_refs
        .replace("spin_up = 50.0", "spin_up = 1.0")
        .replace("average = 40.0", "average = 2.0");
    let case = write_case(tmp.path(), "no_reference", &no_refs);
    let o = run_coarse(&case, &tmp.path().join("no_reference_out"), false);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}{err}");
    assert!(out.contains("UNJUDGED") && !out.contains("PASS"), "{out}");
}

#[test]
fn bad_absorbing_layers_are_refused_naming_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    for (name, layers, expect) in [
        ("twice", sponges(&["west", "west"], 2.0), "two layers on the West edge"),
        ("deep", sponges(&["west"], 19.6), "reaches a body"),
        ("seam", sponges(&["north"], 2.0), "periodic"),
    ] {
        let err = refused(dir.path(), name, &format!("{}\n{layers}", small_case(&[])));
        assert!(err.contains(expect), "{name}: {err}");
    }
}

/// The absorbing layers let the pressure waves of the impulsive start leave the domain: in a
/// steady flow (cylinder, Re 40) between a velocity inlet, an outlet and free-slip sides the
/// drag still rings after 30 L/U without them, and is quiet with them, at the same mean. A
/// characteristic inlet without any layer quiets it too (the waves leave through the inflow).
#[test]
fn absorbing_layers_remove_the_acoustic_ringing_of_the_start() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, layers: &str, inlet: &str| -> serde_json::Value {
        let case = small_case(&[
            ("name = \"cylinder_re100\"", &format!("name = \"{name}\"")),
            ("profile = \"uniform\"\n", &format!("profile = \"uniform\"\n{inlet}")),
            ("reynolds = 100.0", "reynolds = 40.0"),
            ("perturbation = 0.3", "perturbation = 0.0"),
            ("x = [0.0, 60.0]", "x = [0.0, 30.0]"),
            ("y = [-20.0, 20.0]", "y = [-10.0, 10.0]"),
            ("center = [20.0, 0.0]", "center = [10.0, 0.0]"),
            ("south = \"periodic\"", "south = \"free-slip\""),
            ("north = \"periodic\"", "north = \"free-slip\""),
            ("spin_up = 50.0", "spin_up = 30.0"),
            ("average = 40.0", "average = 10.0"),
            (
                "quantities = [\"strouhal\", \"mean_cd\", \"cl_amplitude\"]",
                "quantities = [\"mean_cd\", \"cd_amplitude\"]",
            ),
            ("[[reference]]", &format!("{layers}[[ignored]]")),
        ]);
        // Keep the case's references out (they are for Re 100): cut everything after the marker.
        let case = case.split("[[ignored]]").next().unwrap().to_string();
        let p = write_case(dir.path(), name, &case);
        validate_coarse(&p, &dir.path().join("out"))
    };
    let bare = run("bare", "", "");
    let layered = run("layered", &sponges(&["west", "east", "south", "north"], 2.0), "");
    let characteristic = run("characteristic", "", "characteristic_time = 5.0\n");
    let (ring_bare, ring_layered) = (measured(&bare, "cd_amplitude"), measured(&layered, "cd_amplitude"));
    let (cd_bare, cd_layered) = (measured(&bare, "mean_cd"), measured(&layered, "mean_cd"));
    println!("C_D ringing {ring_bare:.2e} -> {ring_layered:.2e}, mean {cd_bare:.4} -> {cd_layered:.4}");
    assert!(ring_layered < 0.1 * ring_bare, "ringing {ring_bare:.2e} -> {ring_layered:.2e}");
    assert!((cd_layered - cd_bare).abs() < 0.03 * cd_bare, "mean C_D {cd_bare} -> {cd_layered}");
    // Without any layer, a characteristic inlet alone lets the waves out through the inflow.
    let (ring_char, cd_char) = (measured(&characteristic, "cd_amplitude"), measured(&characteristic, "mean_cd"));
    println!("characteristic inlet: C_D ringing {ring_char:.2e}, mean {cd_char:.4}");
    assert!(ring_char < 0.1 * ring_bare, "ringing {ring_bare:.2e} -> {ring_char:.2e}");
    assert!((cd_char - cd_bare).abs() < 0.03 * cd_bare, "mean C_D {cd_bare} -> {cd_char}");
}

#[test]
fn a_negative_characteristic_time_is_refused_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let case = small_case(&[("profile = \"uniform\"\n", "profile = \"uniform\"\ncharacteristic_time = -1.0\n")]);
    let err = refused(dir.path(), "negative", &case);
    assert!(err.contains("inlet.characteristic_time"), "{err}");
}

/// Per-cylinder forces of the three-body pinball against a second solver: HydroGym's Firedrake
/// steady Re 30 solution in its own domain (the bundled case at its 16-cells-per-D level).
#[test]
fn pinball_forces_match_hydrogym_firedrake_steady_solution() {
    let dir = tempfile::tempdir().unwrap();
    let report = validate_coarse(&repo().join("benchmarks/validation/pinball_re30_steady.toml"), dir.path());
    let value = |q: &str| measured(&report, q);
    // The mirror-symmetric grid keeps the unstable symmetric state: equal rear drags, opposite lifts.
    assert!((value("mean_cd_2") - value("mean_cd_3")).abs() < 1e-4);
    assert!((value("mean_cl_2") + value("mean_cl_3")).abs() < 1e-4);
    assert!(value("mean_cl_1").abs() < 1e-3);
    // A steady flow: no frequency is read from the round-off wiggles of its total lift, and the
    // means cover the whole window.
    assert_eq!(report["analysis"]["periods"], 0, "{}", report["analysis"]);
    assert!(report["analysis"].get("strouhal_spectral").is_none_or(|v| v.is_null()));
    schema_check(&report);
    // Three bodies: the history has their drags and lifts beside the totals.
    let csv = std::fs::read_to_string(dir.path().join("pinball_re30_steady/forces.csv")).unwrap();
    assert_eq!(csv.lines().next(), Some("t,c_d,c_l,c_d_1,c_l_1,c_d_2,c_l_2,c_d_3,c_l_3"));
}

#[test]
fn blow_up_exits_1_naming_step_and_cause_with_plots_written() {
    let dir = tempfile::tempdir().unwrap();
    let case = small_case(&[
        ("name = \"cylinder_re100\"", "name = \"blowup\""),
        ("collision = \"regularized\"", "collision = \"bgk\""),
        ("reynolds = 100.0", "reynolds = 2000.0"),
        ("lattice_velocity = 0.05", "lattice_velocity = 0.15"),
        ("coarse = 12", "coarse = 40"),
        ("x = [0.0, 60.0]", "x = [0.0, 16.0]"),
        ("y = [-20.0, 20.0]", "y = [-4.0, 4.0]"),
        ("center = [20.0, 0.0]", "center = [4.0, 0.0]"),
    ]);
    let p = write_case(dir.path(), "blowup", &case);
    let out = dir.path().join("out");
    let o = run_coarse(&p, &out, false);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(1), "stdout: {stdout}\nstderr: {stderr}");
    assert!(stdout.contains("DIVERGED") && stdout.contains("diverged at step"), "{stdout}");
    for plot in ["forces.png", "spectrum.png", "vorticity.png"] {
        assert!(out.join("blowup").join(plot).exists(), "{plot} missing after the blow-up");
    }
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("blowup.json")).unwrap()).unwrap();
    assert_eq!(report["status"], "diverged");
    schema_check(&report);
}

#[test]
fn an_unseen_case_file_runs_and_passes() {
    let dir = tempfile::tempdir().unwrap();
    let case = repo().join("tests/cases/schaefer_turek_2d1.toml");
    let out = dir.path().join("out");
    let o = run_coarse(&case, &out, false);
    let (stdout, stderr) = text(&o);
    println!("{stdout}");
    assert_eq!(o.status.code(), Some(0), "stdout: {stdout}\nstderr: {stderr}");
    assert!(stdout.contains("mean_cd") && stdout.contains("PASS"));
    // stderr is a pipe here, as in a log file: progress comes as a line per tenth of the run.
    let tenths: Vec<&str> = stderr.lines().filter(|l| l.starts_with("schaefer_turek_2d1: ")).collect();
    assert_eq!(tenths.len(), 10, "{stderr}");
    assert!(
        tenths[0].starts_with("schaefer_turek_2d1: 10% (") && tenths[9].contains("100% ("),
        "{stderr}"
    );
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("schaefer_turek_2d1.json")).unwrap()).unwrap();
    schema_check(&report);
    assert_eq!(report["status"], "pass");
    assert_eq!(report["family"], "channel");
    // Steady flow: no shedding, so no Strouhal number.
    let st = report["quantities"]
        .as_array()
        .unwrap()
        .iter()
        .find(|q| q["name"] == "strouhal")
        .unwrap();
    assert!(st["measured"].is_null());
    // The recirculation bubble behind it, from the mean wake on its centreline.
    let l_r = measured(&report, "recirculation_length");
    assert!((0.8..0.9).contains(&l_r), "L_r / D = {l_r}");
    for plot in ["forces.png", "spectrum.png", "vorticity.png", "wake.png"] {
        assert!(out.join("schaefer_turek_2d1").join(plot).exists());
    }
    // The force history re-analyses to the report: its mean drag over the report's window.
    let csv = std::fs::read_to_string(out.join("schaefer_turek_2d1/forces.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("t,c_d,c_l"));
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    let t_end = report["parameters"]["spin_up"].as_f64().unwrap() + report["parameters"]["average"].as_f64().unwrap();
    assert!(
        (rows.last().unwrap()[0] - t_end).abs() < 0.02,
        "history ends at {}",
        rows.last().unwrap()[0]
    );
    let spacing = rows[1][0] - rows[0][0];
    assert!(spacing > 0.0 && spacing <= 0.01 + 1e-9, "{spacing}");
    let window = report["analysis"]["window"].as_array().unwrap();
    let (t0, t1) = (window[0].as_f64().unwrap(), window[1].as_f64().unwrap());
    let in_window: Vec<f64> = rows.iter().filter(|r| r[0] >= t0 && r[0] <= t1).map(|r| r[1]).collect();
    let mean = in_window.iter().sum::<f64>() / in_window.len() as f64;
    let reported = measured(&report, "mean_cd");
    assert!((mean - reported).abs() < 1e-3 * reported, "csv mean {mean}, report {reported}");
}

#[test]
fn committed_validation_reports_match_the_schema() {
    let dir = repo().join("results/validation");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|e| e == "json") {
            let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
            if v["schema"] == "hgym/validation/v1" {
                schema_check(&v);
                n += 1;
            }
        }
    }
    assert!(n >= 2, "expected the committed cylinder reports in {}", dir.display());
}

#[test]
fn json_output_is_machine_readable() {
    let dir = tempfile::tempdir().unwrap();
    let case = repo().join("tests/cases/schaefer_turek_2d1.toml");
    schema_check(&validate_coarse(&case, &dir.path().join("out")));
}

/// Every lattice and operator passes its Taylor-Green check (BGK in 3D used to fail it: the
/// vortex started without its pressure); the 3D rows also time their kernel's free streaming.
#[test]
fn bench_quick_reports_mlups_and_roofline_fraction() {
    for (lattice, collision, bytes) in [("d2q9", "regularized", 72), ("d3q19", "bgk", 152), ("d3q27", "regularized", 216)] {
        let v = json_of(&["bench", "lbm", "--quick", "--json", "--lattice", lattice, "--collision", collision]);
        let rows = v["rows"].as_array().unwrap();
        assert_eq!(rows.len(), 6);
        for r in rows {
            assert!(r["mlups"].as_f64().unwrap() > 0.0);
            assert!(r["roofline_fraction"].as_f64().unwrap() > 0.0);
            assert!(r["check_error"].as_f64().unwrap() < 0.01);
            // The kernel without its collision, timed beside it in 3D.
            assert_eq!(
                r["streaming_mlups"].as_f64().is_some_and(|m| m > 0.0),
                lattice != "d2q9",
                "{lattice}: {r}"
            );
        }
        assert_eq!(v["bytes_per_cell"], bytes);
    }
}

/// `--size` replaces the memory-bound size; a malformed size or one of the other dimension is a
/// usage error that says what to give.
#[test]
fn bench_lbm_size_is_checked_and_used() {
    let v = json_of(&["bench", "lbm", "--quick", "--json", "--size", "96x40"]);
    let last = &v["rows"].as_array().unwrap()[2];
    assert_eq!((last["nx"].as_u64(), last["ny"].as_u64()), (Some(96), Some(40)));
    assert!(["stream", "memcpy"].contains(&last["copy_method"].as_str().unwrap()));
    for (size, says) in [("12x3", "NXxNY"), ("64x64x64", "does not fit --lattice d2q9"), ("ax8", "NXxNY")] {
        let o = hgym(&["bench", "lbm", "--quick", "--size", size]);
        let (_, err) = text(&o);
        assert_eq!(o.status.code(), Some(2), "{size}: {err}");
        assert!(err.contains(says), "{size}: {err}");
    }
}

/// `hgym bench channel --quick`: steps/s and simulated t+ per second of the minimal and the full
/// channel, 1 and 2 threads, consistent with each other; no peer, so nothing is judged.
#[test]
fn bench_channel_quick_reports_simulated_time_per_second() {
    let v = json_of(&["bench", "channel", "--quick", "--json", "--threads", "2"]);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 4, "{v}");
    for r in rows {
        let f = |k: &str| r[k].as_f64().unwrap();
        assert!(f("steps_per_s") > 0.0);
        assert!((f("t_plus_per_s") - f("steps_per_s") * f("dt_plus")).abs() < 1e-9 * f("t_plus_per_s"));
        assert!((f("bulk_time_per_s") - f("steps_per_s") * f("dt")).abs() < 1e-9 * f("bulk_time_per_s"));
    }
    assert!(v["peer"].is_null() && v["pass"] == true);
}

#[test]
fn bench_refine_quick_reports_the_ratio_to_the_uniform_kernel() {
    let v = json_of(&["bench", "refine", "--quick", "--json"]);
    assert_eq!(v["schema"], "hgym/bench-refine/v1");
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for r in rows {
        let (uniform, refined) = (r["uniform_mlups"].as_f64().unwrap(), r["refined_mlups"].as_f64().unwrap());
        assert!(uniform > 0.0 && refined > 0.0);
        assert!((r["ratio"].as_f64().unwrap() - refined / uniform).abs() < 1e-9);
        // 128^2 coarse nodes and the 129^2 fine nodes over the middle 64^2 cells, stepped twice.
        assert_eq!(r["node_updates_per_step"], 128 * 128 + 2 * 129 * 129);
        for e in r["check_error"].as_array().unwrap() {
            assert!(e.as_f64().unwrap() < 0.01, "{v}");
        }
    }
    // In 3D: a 64^3 box and the 65^3 fine nodes over its middle 32^3 cells.
    let v = json_of(&["bench", "refine", "--lattice", "d3q19", "--quick", "--json"]);
    assert_eq!(v["lattice"], "d3q19");
    for r in v["rows"].as_array().unwrap() {
        assert_eq!(r["node_updates_per_step"], 64 * 64 * 64 + 2 * 65 * 65 * 65);
        for e in r["check_error"].as_array().unwrap() {
            assert!(e.as_f64().unwrap() < 0.01, "{v}");
        }
    }
}

#[test]
fn bench_python_without_the_package_says_how_to_build_it() {
    let o = Command::new(env!("CARGO_BIN_EXE_hgym"))
        .args(["bench", "python", "--quick"])
        .env("HGYM_PYTHON", "/nonexistent/bin/python")
        .output()
        .unwrap();
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("/nonexistent/bin/python not found") && err.contains("make python"),
        "{err}"
    );
}

#[test]
fn bench_envs_times_only_the_families_asked_for() {
    let o = hgym(&["bench", "envs", "--family", "pinbal"]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("unknown family 'pinbal'") && err.contains("stenotic_pipe"), "{err}");

    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_hgym"))
        .args(["bench", "envs", "--family", "stenotic_pipe", "--quick", "--actions", "1", "--json"])
        .env("HGYM_CACHE", dir.path())
        .output()
        .unwrap();
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    let rows: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    let rows = rows.as_array().unwrap();
    let ids: Vec<&str> = rows.iter().filter_map(|r| r["id"].as_str()).collect();
    assert_eq!(
        ids,
        ["StenoticPipe_2D_Re100", "StenoticPipe_3D_Re100"],
        "the family's 2D ID and its 3D grid: {out}"
    );
    for r in rows {
        assert_eq!(r["family"], "stenotic_pipe");
        assert_eq!(r["level"], "coarse");
        assert!(r["actions_per_s"].as_f64().unwrap() > 0.0);
        let outside = r["outside_share"].as_f64().unwrap();
        assert!((0.0..1.0).contains(&outside), "share of an action outside the solver: {outside}");
    }
}

#[test]
fn envs_lists_every_id_and_show_round_trips() {
    let o = hgym(&["envs"]);
    assert!(o.status.success());
    let (out, _) = text(&o);
    for spec in hgym::env::registry::lbm_specs() {
        assert!(out.contains(&spec.id), "{} missing from `hgym envs`", spec.id);
    }
    // The deviation columns read the committed table (benchmarks/envs/fidelity.toml).
    let row = out.lines().find(|l| l.starts_with("Cylinder_2D_Re100 ")).unwrap();
    let spec = hgym::env::lbm_spec("Cylinder_2D_Re100").unwrap();
    let coarse = hgym::fidelity::committed(&spec, Level::Coarse).expect("a committed coarse row");
    assert!(row.contains(&coarse.summary()), "{row}");
    let row = out.lines().find(|l| l.starts_with("Cavity_2D_Re7500 ")).unwrap();
    assert!(row.split_whitespace().rev().take(2).all(|c| c == "-"), "no references: {row}");
    let o = hgym(&["envs", "show", "Cylinder_2D_Re200"]);
    assert!(o.status.success());
    let shown: hgym::env::EnvSpec = toml::from_str(&text(&o).0).expect("`envs show` prints valid TOML");
    assert_eq!(shown, hgym::env::registry::lbm_spec("Cylinder_2D_Re200").unwrap());
}

/// `hgym validate --env ID` runs the environment's own flow (its domain, its coarse grid) and
/// reports the deviations from its family's references: exit 1 here, because the coarse
/// cylinder's mean drag is 14 % above the unconfined literature value; the row it prints is
/// the committed table's (the table is refreshed by `--record` after every flow change).
#[test]
fn validate_env_runs_the_environment_flow_and_reports_deviations() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let o = hgym(&["validate", "--env", "Cylinder_2D_Re100", "--level", "coarse", "--out", out]);
    let (stdout, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{stdout}{err}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("envs/Cylinder_2D_Re100-coarse.json")).unwrap()).unwrap();
    schema_check(&report);
    assert_eq!(report["origin"], "env:Cylinder_2D_Re100");
    assert_eq!(
        report["parameters"]["nx"], 320,
        "the environment's [0, 40] x [-10, 10] at 8 cells per D"
    );
    let spec = hgym::env::lbm_spec("Cylinder_2D_Re100").unwrap();
    let committed = hgym::fidelity::committed(&spec, Level::Coarse).expect("a committed coarse row");
    assert!(stdout.contains(&committed.summary()), "{stdout}");
    // No references for the cavity: bad input, exit 2, naming the way out.
    let o = hgym(&["validate", "--env", "Cavity_2D_Re7500", "--level", "coarse", "--out", out]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).1.contains("--env all"), "{}", text(&o).1);
}

/// The example in `hgym export --help` works, from the repository root, on what it commits.
#[test]
fn the_export_help_example_runs_on_the_committed_results() {
    let help = text(&hgym(&["export", "--help"])).0;
    let start = help.find("`hgym export ").expect("the help shows an example");
    let example = &help[start + 1..start + 1 + help[start + 1..].find('`').unwrap()];
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("dataset");
    let args: Vec<String> = example
        .split_whitespace()
        .skip(1)
        .map(|a| if a == "OUT" { out.display().to_string() } else { a.to_string() })
        .collect();
    let o = Command::new(env!("CARGO_BIN_EXE_hgym"))
        .args(&args)
        .current_dir(repo())
        .output()
        .unwrap();
    let (stdout, err) = text(&o);
    assert!(o.status.success(), "`{example}`: {stdout}{err}");
    assert!(out.join("README.md").is_file(), "`{example}` wrote no dataset card");
}

/// A reader that closes the pipe early (`hgym envs | head -1`) ends hgym quietly with exit 0.
#[test]
fn a_closed_stdout_pipe_exits_0_without_a_panic() {
    for args in [vec!["envs"], vec!["envs", "show", "Cylinder_2D_Re100"], vec!["validate", "--list"]] {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let o = Command::new(env!("CARGO_BIN_EXE_hgym"))
            .args(&args)
            .stdout(writer)
            .output()
            .expect("run hgym");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

#[test]
fn calibrating_over_no_actions_exits_2_for_every_family() {
    for id in ["Cylinder_2D_Re100", "Kolmogorov_2D_Re40"] {
        let o = hgym(&["envs", "calibrate", id, "--actions", "0", "--table", "/nonexistent/table.json"]);
        let (_, err) = text(&o);
        assert_eq!(o.status.code(), Some(2), "{id}: {err}");
        assert!(err.contains("--actions must be at least 1"), "{id}: {err}");
    }
}

#[test]
fn unknown_env_id_exits_2_with_suggestions() {
    for args in [
        vec!["envs", "show", "Cylinder_2D_Re10"],
        vec!["run", "--env", "Cylinder_2D_Re10", "--steps", "1"],
    ] {
        let o = hgym(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let (_, err) = text(&o);
        assert!(
            err.contains("unknown environment ID 'Cylinder_2D_Re10'") && err.contains("Cylinder_2D_Re100"),
            "{err}"
        );
    }
}

#[test]
fn run_writes_metrics_plots_and_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("runs");
    let run = || {
        Command::new(env!("CARGO_BIN_EXE_hgym"))
            .args([
                "run",
                "--env",
                "RotaryCylinder_2D_Re100",
                "--policy",
                "random",
                "--steps",
                "5",
                "--res",
                "coarse",
                "--seed",
                "3",
            ])
            .arg("--out")
            .arg(&out)
            .env("HGYM_CACHE", dir.path().join("cache"))
            .output()
            .unwrap()
    };
    let o = run();
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    // The first reset spins the flow up; stderr is a pipe, so it reports a line per tenth.
    let spin_up: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("spin-up of RotaryCylinder_2D_Re100: "))
        .collect();
    assert_eq!(spin_up.len(), 10, "{stderr}");
    assert!(spin_up[9].contains(": 100% ("), "{stderr}");
    let folder = out.join("RotaryCylinder_2D_Re100-random-seed3");
    for f in ["manifest.json", "metrics.json", "rollout.png", "vorticity.png"] {
        assert!(folder.join(f).exists(), "{f} missing");
    }
    let m: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(folder.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(m["actions_run"], 5);
    assert_eq!(m["truncated"], true);
    assert_eq!(m["spec_hash"].as_str().unwrap().len(), 64);
    // The developed flow was cached for the next run, which does not spin up again.
    assert!(std::fs::read_dir(dir.path().join("cache")).unwrap().count() >= 1);
    let o = run();
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    assert!(!stderr.contains("spin-up"), "{stderr}");
}

/// The Schäfer-Turek case at its coarse level (D = 20 cells) with a 2:1 patch around the
/// cylinder: the drag moves towards the benchmark like the uniformly finer grid's, and the report
/// records the patch.
/// A case can choose the recursive-regularised operator: the Schäfer-Turek benchmark passes with
/// it at the coarse level, and the report names it (and still matches the schema).
#[test]
fn a_case_with_the_recursive_operator_passes_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let plain = std::fs::read_to_string(repo().join("tests/cases/schaefer_turek_2d1.toml")).unwrap();
    assert!(plain.contains("collision = \"regularized\""));
    let body = plain
        .replace("name = \"schaefer_turek_2d1\"", "name = \"st_recursive\"")
        .replace("collision = \"regularized\"", "collision = \"recursive\"");
    let case = write_case(dir.path(), "st_recursive", &body);
    let report = validate_coarse(&case, &dir.path().join("out"));
    schema_check(&report);
    assert_eq!(report["parameters"]["collision"], "recursive");
    println!("Schäfer-Turek 2D-1, recursive operator: C_D {:.4}", measured(&report, "mean_cd"));

    // An unknown operator is refused naming the field and the choices.
    let err = refused(
        dir.path(),
        "st_bad",
        &body.replace("collision = \"recursive\"", "collision = \"cumulant\""),
    );
    assert!(err.contains("cumulant") && err.contains("recursive"), "{err}");
}

#[test]
fn a_refined_case_runs_records_its_patch_and_improves_the_drag() {
    let dir = tempfile::tempdir().unwrap();
    let plain = std::fs::read_to_string(repo().join("tests/cases/schaefer_turek_2d1.toml")).unwrap();
    let refined =
        plain.replace("name = \"schaefer_turek_2d1\"", "name = \"st_refined\"") + "\n[refinement]\nregions = [[0.8, 6.0, 0.3, 3.8]]\n";
    let case = write_case(dir.path(), "st_refined", &refined);
    let out = dir.path().join("out");
    let o = run_coarse(&case, &out, false);
    let (stdout, stderr) = text(&o);
    println!("{stdout}");
    assert_eq!(o.status.code(), Some(0), "stdout: {stdout}\nstderr: {stderr}");
    assert!(stdout.contains("refined 2:1 x 1 around the bodies"), "{stdout}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("st_refined.json")).unwrap()).unwrap();
    schema_check(&report);
    let r = &report["parameters"]["refinement"];
    assert_eq!(r["cells_per_length"], 40.0);
    assert_eq!(r["patches"].as_array().map(Vec::len), Some(1));
    let plain_report = validate_coarse(&repo().join("tests/cases/schaefer_turek_2d1.toml"), &dir.path().join("plain"));
    let (c_plain, c_refined) = (measured(&plain_report, "mean_cd"), measured(&report, "mean_cd"));
    println!("Schäfer-Turek C_D at 20 cells: {c_plain:.4}; with a 40-cell patch: {c_refined:.4} (benchmark 5.5795)");
    assert!(
        (c_refined - 5.5795).abs() < (c_plain - 5.5795).abs(),
        "the patch should move C_D towards 5.5795: {c_plain} -> {c_refined}"
    );

    // A region that leaves the domain is refused before anything runs.
    let bad = refined.replace("regions = [[0.8, 6.0, 0.3, 3.8]]", "regions = [[0.8, 6.0, -1.0, 3.8]]");
    let err = refused(dir.path(), "st_bad", &bad);
    assert!(err.contains("refinement.regions") && err.contains("inside the domain"), "{err}");
}

/// A 3D case (a `[span]`) runs through the same command: the sphere case on a small box at 4
/// cells per D for a few D/U. Its drag is far from converged (the test checks the path, not the
/// number: exit 0 or 1, a schema-valid report with the third axis, a finite positive drag and
/// the mid-span vorticity plot); a span that is not a whole number of cells is refused first.
#[test]
fn a_3d_case_runs_through_the_span_path() {
    let dir = tempfile::tempdir().unwrap();
    let template = std::fs::read_to_string(repo().join("benchmarks/validation/sphere_re100.toml")).unwrap();
    let mut body = template.clone();
    for (from, to) in [
        ("center = [6.0, 6.0, 6.0]", "center = [3.0, 3.0, 3.0]"),
        ("x = [0.0, 20.0]", "x = [0.0, 10.0]"),
        ("y = [0.0, 12.0]", "y = [0.0, 6.0]"),
        ("z = [0.0, 12.0]", "z = [0.0, 6.0]"),
        ("coarse = 8", "coarse = 4"),
        ("spin_up = 30.0", "spin_up = 2.0"),
        ("average = 10.0", "average = 2.0"),
    ] {
        assert!(body.contains(from), "template has no '{from}'");
        body = body.replace(from, to);
    }
    let case = write_case(dir.path(), "sphere_small", &body);
    let out = dir.path().join("out");
    let o = run_coarse(&case, &out, false);
    let (stdout, stderr) = text(&o);
    assert!(matches!(o.status.code(), Some(0 | 1)), "stdout: {stdout}\nstderr: {stderr}");
    assert!(
        stderr.contains("40 x 24 x 24 nodes"),
        "the grid and its memory come first: {stderr}"
    );
    assert!(stdout.contains("40 x 24 x 24 cells"), "{stdout}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("sphere_re100.json")).unwrap()).unwrap();
    schema_check(&report);
    assert_eq!(report["parameters"]["nz"], 24);
    let cd = measured(&report, "mean_cd");
    assert!(cd.is_finite() && cd > 0.5 && cd < 5.0, "C_D {cd}");
    assert!(out.join("sphere_re100/vorticity.png").exists());

    let err = refused(dir.path(), "ragged_span", &body.replace("z = [0.0, 6.0]", "z = [0.0, 6.1]"));
    assert!(err.contains("span.z") && err.contains("whole number of cells"), "{err}");
}
