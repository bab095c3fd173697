//! The closed-form start of laws with a yield stress (`identify --start closed-form` on
//! `Plastic` and `NortonHoff`; `indentify_study::closed_form_start`, docs/analysis.md
//! "Closed-form starts for laws with a yield stress"): on synthesized curves of known truth
//! the start sets `E`, `sY` (and Dao's `n` under a 70.3-degree cone) near the truth, says
//! what it set and what it kept; a fit from it ends where the fit from the configuration's
//! start ends.

mod common;

use common::{example, noisy_example as options};

use indentify_study::ConfigSource;
use indentify_study::closed_form_start::{ClosedFormStart, apply};
use indentify_study::identify::{self, IdentifyOptions, IdentifyOutcome};

/// `plastic-power-cone.ron` on a smaller mesh with its unloading resolved where the force
/// falls (to 0.08 mm in 10 steps, then to 0 in 2): the unloading slope and the work ratio
/// need it (the example unloads to 0 in 20 equal steps, the force reaching zero in two).
fn power_cone() -> IdentifyOptions {
    let name = "plastic-power-cone.ron";
    let text = std::fs::read_to_string(example(name)).expect("example");
    let from = "            (duration: 1.0, depth: 0.1, steps: 20), // load\n            (duration: 1.0, depth: 0.0, steps: 20), // unload\n";
    assert!(text.contains(from));
    let to = "            (duration: 1.0, depth: 0.1, steps: 12),\n            (duration: 0.2, depth: 0.08, steps: 10),\n            (duration: 0.8, depth: 0.0, steps: 2),\n";
    let mut o = options(name, &["specimen.nr=12", "specimen.nz=12"]);
    o.config = ConfigSource::Text {
        text: text.replace(from, to),
        name: "plastic-power-cone, small".into(),
    };
    o
}

fn prefit(o: &IdentifyOptions) -> ClosedFormStart {
    let mut s = identify::setup(identify::resolve(o).expect("resolve"), o).expect("setup");
    apply(&mut s)
}

fn value(c: &ClosedFormStart, n: &str) -> f64 {
    c.values.iter().find(|(m, _)| m == n).expect(n).1
}

#[test]
fn a_power_law_under_the_berkovich_cone_starts_from_dao_s_reverse_analysis() {
    let c = prefit(&power_cone());
    eprintln!("{}", c.summary());
    eprintln!("half-space {:?}, {:.3} s", c.half_space, c.seconds);
    assert!(c.method.contains("Dao"), "{c:?}");
    let names: Vec<&str> = c.values.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["E", "sY", "n"], "{c:?}");
    // the truth of the law section: E 200000, sY 400, n 0.2 (the start: 150000, 300, 0.3)
    // E within 10% (measured: 187161, -6.4%); sY and n are the "mystical" pair one cone
    // does not separate: only inside their bounds
    let e = value(&c, "E");
    assert!((e / 200_000.0 - 1.0).abs() < 0.1, "{c:?}");
    assert!(value(&c, "sY") > 1.0 && value(&c, "n") <= 0.5, "{c:?}");
    assert!(
        c.notes.iter().any(|n| n.contains("calibration run")),
        "{c:?}"
    );
    assert!(c.rms_rel.is_some() && c.half_space.len() == 3, "{c:?}");
}

#[test]
fn norton_hoff_under_a_68_degree_cone_starts_from_tabor_s_hardness() {
    let c = prefit(&options("r2-norton-hoff.ron", &[]));
    eprintln!("{}", c.summary());
    eprintln!("half-space {:?}, {:.3} s", c.half_space, c.seconds);
    assert!(c.method.contains("Tabor"), "{c:?}");
    // truth E 100000, sY 500 (the start 130000, 1000): measured 100845 and 461
    assert!((value(&c, "E") / 100_000.0 - 1.0).abs() < 0.1, "{c:?}");
    assert!((value(&c, "sY") / 500.0 - 1.0).abs() < 0.3, "{c:?}");
    assert!(c.notes.iter().any(|n| n.contains("K, m keep")), "{c:?}");
    assert!(
        c.notes
            .iter()
            .any(|n| n.contains("overstress") && !n.contains("not corrected")),
        "{c:?}"
    );
    assert!(c.notes.iter().any(|n| n.contains("not corrected")), "{c:?}");
    // no calibration run: the values are the analysis'
    assert_eq!(c.values, c.half_space);
    assert!(c.rms_rel.is_none());
}

fn counts(o: &IdentifyOutcome) -> String {
    format!(
        "{} iterations, {} forward, {} sensitivity solves, fit {:.1} s; {}",
        o.result.iterations,
        o.result.forward_solves,
        o.result.sensitivity_solves,
        o.result.seconds,
        o.result.stop_reason
    )
}

/// Every free parameter of `a` within `tol` standard deviations (of `a`) of `b`'s.
fn same_fit(a: &IdentifyOutcome, b: &IdentifyOutcome, tol: f64) {
    assert!(
        a.converged() && b.converged(),
        "{} / {}",
        a.result.stop_reason,
        b.result.stop_reason
    );
    for p in a.result.params.iter().filter(|p| p.free) {
        let sd = a.std_dev(p.name).expect("a deviation");
        let other = b.value(p.name).expect("the same parameter");
        let z = (p.value - other).abs() / sd;
        eprintln!("{}: {} against {} ({z:.4} sd)", p.name, p.value, other);
        assert!(z <= tol, "{}: {} against {other}, {z} sd", p.name, p.value);
    }
}

#[test]
fn a_plastic_fit_from_the_yield_start_ends_where_it_ends_from_the_configuration() {
    let base = power_cone();
    let mut closed = base.clone();
    closed.closed_form_start = true;
    let a = identify::run(&closed, &mut ()).expect("closed-form start");
    let b = identify::run(&base, &mut ()).expect("configuration's start");
    eprintln!("{}", a.start.as_ref().expect("start").summary());
    eprintln!("closed form: {}", counts(&a));
    eprintln!("configuration: {}", counts(&b));
    same_fit(&a, &b, 0.1);
}

/// One case's fits: from the configuration's start, from the closed-form start, and (when
/// the start kept a value other than its half-space one) from the half-space values.
fn measure_case(name: &str, base: IdentifyOptions) {
    let fwd = {
        let s = identify::setup(identify::resolve(&base).expect("resolve"), &base).expect("setup");
        let start: Vec<f64> = s
            .id_cfg
            .params
            .iter()
            .map(|p| p.value.unwrap_or(0.0))
            .collect();
        let clock = std::time::Instant::now();
        indentify_identify::Evaluator::new(&s.problem)
            .and_then(|mut ev| ev.forces(&start))
            .expect("forward");
        clock.elapsed().as_secs_f64()
    };
    let mut closed = base.clone();
    closed.closed_form_start = true;
    let b = identify::run(&base, &mut ()).expect("configuration's start");
    let a = identify::run(&closed, &mut ()).expect("closed-form start");
    let c = a.start.clone().expect("start");
    eprintln!("{name}: one forward {fwd:.3} s; {}", c.summary());
    eprintln!("{name}: half-space {:?}", c.half_space);
    let line = |what: &str, o: &IdentifyOutcome| {
        eprintln!(
            "{name}: {what}: {} = {:.1} forward runs",
            counts(o),
            o.wall_seconds / fwd
        );
        for p in o.result.params.iter().filter(|p| p.free) {
            let sd = b.std_dev(p.name).unwrap_or(f64::NAN);
            let other = b.value(p.name).unwrap_or(f64::NAN);
            eprintln!(
                "{name}:   {} {:.6e} (start {:.6e}) against {:.6e}: {:.4} sd",
                p.name,
                p.value,
                p.start,
                other,
                (p.value - other).abs() / sd
            );
        }
    };
    line("configuration start", &b);
    line("closed-form start", &a);
    if c.half_space != c.values {
        let mut half = base.clone();
        half.overrides.starts = c.half_space.clone();
        let h = identify::run(&half, &mut ()).expect("half-space start");
        line("uncorrected (half-space) start", &h);
    }
}

/// `cargo test -p indentify-study --test closed_form_yield -- --ignored --nocapture`: the
/// fits from the configuration's start and from the yield start, back to back on one
/// thread (a measurement, not a check; docs/performance.md).
#[test]
#[ignore = "a measurement: minutes on a loaded machine"]
fn measure_fits_from_the_yield_start() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let which = std::env::var("YIELD_CASES").unwrap_or_else(|_| "power,r2".into());
    pool.install(|| {
        for case in which.split(',') {
            match case {
                "power" => measure_case("power-cone", power_cone()),
                "sphere" => measure_case("sphere-linear", sphere_linear()),
                "r2" => measure_case("r2-norton-hoff", options("r2-norton-hoff.ron", &[])),
                "ht-nh" => {
                    let mut o = IdentifyOptions::new(ConfigSource::Path(example("real/ht-nh.ron")));
                    o.refine = false;
                    o.figures = false;
                    o.jobs = Some(1);
                    measure_case("ht-nh", o)
                }
                "anon" => {
                    let mut o = IdentifyOptions::new(ConfigSource::Path(example(
                        "real/anon-power-norton.ron",
                    )));
                    o.refine = false;
                    o.figures = false;
                    o.jobs = Some(1);
                    measure_case("anon-power-norton", o)
                }
                other => panic!("unknown case {other}"),
            }
        }
    });
}

/// The real Anton Paar Berkovich record under `Plastic(Power, Norton)`
/// (`examples/real/anon-power-norton.ron`): its unloading stops at a tenth of the force,
/// so Dao's route (which needs the work ratio) gives way to the stiffness and Tabor's
/// hardness, and says so; `E` is set (2675 MPa against the configuration's 2000 and the
/// fit's 2290, docs/tutorial-real-data.md); the configuration's `K`, `m` put the rate's
/// overstress above the representative stress, so `sY` keeps its start (a note); no
/// forward run is made.
#[test]
fn the_real_berkovich_record_starts_from_the_stiffness_and_says_why() {
    let mut o = IdentifyOptions::new(ConfigSource::Path(example("real/anon-power-norton.ron")));
    o.jobs = Some(1);
    let c = prefit(&o);
    eprintln!("{}", c.summary());
    eprintln!("half-space {:?}, {:.3} s", c.half_space, c.seconds);
    assert!(c.method.contains("Tabor"), "{c:?}");
    assert!(
        c.notes
            .iter()
            .any(|n| n.contains("Dao's reverse analysis") && n.contains("zero force")),
        "{c:?}"
    );
    let names: Vec<&str> = c.values.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["E"], "{c:?}");
    assert!((value(&c, "E") / 2290.0 - 1.0).abs() < 0.25, "{c:?}");
    assert!(
        c.notes
            .iter()
            .any(|n| n.contains("sY keeps") && n.contains("overstress")),
        "{c:?}"
    );
    assert!(
        c.notes.iter().any(|n| n.contains("sY, n, K, m keep")),
        "{c:?}"
    );
    assert!(c.rms_rel.is_none(), "{c:?}");
}

/// A sphere on `Plastic(Linear)` (synthesized, 2% noise): the stiffness and Tabor's route,
/// `sY` through the linear hardening at `0.2 a/R` with the configuration's `H`, which
/// keeps its start (a note); corrected by a calibration run (rate-independent).
fn sphere_linear() -> IdentifyOptions {
    let text = "(
        specimen: Cylinder(radius: 10.0, height: 10.0, nr: 12, nz: 12, grading_r: 1.3, grading_z: 1.3),
        punch: Sphere(radius: 0.5),
        contact: Vertical,
        kinematics: Small,
        law: Plastic(E: 100000.0, nu: 0.3, sY: 300.0, hardening: Linear(H: 2000.0)),
        history: (segments: [
            (duration: 1.0, depth: 0.05, steps: 12),
            (duration: 0.2, depth: 0.045, steps: 10),
            (duration: 0.8, depth: 0.0, steps: 2),
        ]),
        identify: (
            params: {
                \"E\": Free(start: 150000.0, lower: 1000.0, upper: 1e6),
                \"nu\": Fixed(value: 0.3),
                \"sY\": Free(start: 600.0, lower: 1.0, upper: 10000.0),
                \"H\": Free(start: 2000.0, lower: 0.0, upper: 1e5, scaling: Linear),
            },
            method: Lm,
        ),
    )";
    let mut o = options("r0-elastic.ron", &[]);
    o.config = ConfigSource::Text {
        text: text.into(),
        name: "sphere linear".into(),
    };
    o
}

#[test]
fn a_sphere_on_linear_hardening_starts_from_tabor_s_hardness() {
    let c = prefit(&sphere_linear());
    eprintln!("{}", c.summary());
    eprintln!("half-space {:?}", c.half_space);
    assert!(
        c.method.contains("Tabor") && c.method.contains("sphere"),
        "{c:?}"
    );
    let names: Vec<&str> = c.values.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["E", "sY"], "{c:?}");
    assert!(c.notes.iter().any(|n| n.contains("H keeps")), "{c:?}");
    assert!(
        c.notes.iter().any(|n| n.contains("calibration run")),
        "{c:?}"
    );
    // truth E 100000, sY 300 (start 150000, 600): measured 93765 and 321 (the half-space
    // values 68788 and 261 before the correction)
    assert!((value(&c, "E") / 100_000.0 - 1.0).abs() < 0.15, "{c:?}");
    assert!((value(&c, "sY") / 300.0 - 1.0).abs() < 0.2, "{c:?}");
}
