//! CalculiX under a concentrated force (`cargo xtask calculix --drive force`,
//! docs/validation-load-control.md §11), without `ccx`: the load-controlled deck (the rigid
//! punch tied to its reference node, the `*CLOAD` with the history's corners, the soft
//! spring and the soft start), the `.dat` parser, and the committed curves: our
//! load-controlled run driven by the contact force CalculiX carried is recomputed here and
//! must give the committed depths (to solver tolerance) and stay within the stated
//! tolerance of CalculiX's depths, so a change of our solver that moves the
//! load-controlled depth fails this test.

use indentify_testkit::{cone68, cylinder_rz, workspace_root as root};
use xtask::calculix::{self, DeckOptions, FiniteElastic, Material, force};

#[test]
fn force_deck_ties_the_punch_to_its_reference_node_and_loads_it() {
    let mesh = cylinder_rz(2.0, 3, 2, 1.3);
    let punch = cone68();
    let m = Material::maxwell(2e4, 0.3, 3e4);
    let o = DeckOptions {
        punch_segments: 4,
        ..DeckOptions::default()
    };
    let history = force::force_history(300.0).unwrap();
    assert_eq!(history.schedule.t.len(), 91);
    let deck = force::deck("t", &mesh, &punch, &m, &history, &o).unwrap();
    let (n0, np) = (mesh.nodes.len(), 4);
    let reference = n0 + np + 2;
    // every strip node but the reference tied to it in u_z: 2 np + 1 equations
    let eqs = deck.split("*EQUATION\n").nth(1).unwrap();
    let rows: Vec<&str> = eqs.lines().take_while(|l| !l.starts_with('*')).collect();
    assert_eq!(rows.len(), 2 * (2 * np + 1));
    for n in (n0 + 1..=n0 + 2 * np + 2).filter(|&n| n != reference) {
        assert!(
            rows.contains(&format!("{n}, 2, 1.0, {reference}, 2, -1.0").as_str()),
            "node {n}"
        );
    }
    // the force on the reference node (full circle), ramp, hold, unload to 0.4 P
    assert!(deck.contains(&format!(
        "*CLOAD, AMPLITUDE=FORCE\n{reference}, 2, -3.000000000000e2\n"
    )));
    let amp = deck.split("*AMPLITUDE, NAME=FORCE\n").nth(1).unwrap();
    let corners: Vec<Vec<f64>> = amp
        .lines()
        .take_while(|l| !l.starts_with('*'))
        .map(|l| l.split(',').map(|x| x.trim().parse().unwrap()).collect())
        .collect();
    let expected = [[0.0, 0.0], [1.0, 1.0], [2.0, 1.0], [3.0, 0.4]];
    assert_eq!(corners.len(), 4);
    for (c, e) in corners.iter().zip(expected) {
        assert!(
            (c[0] - e[0]).abs() < 1e-12 && (c[1] - e[1]).abs() < 1e-12,
            "{c:?}"
        );
    }
    // no prescribed depth; the punch keeps u_r = 0, the spring's top is fixed
    assert!(!deck.contains("AMPLITUDE=DEPTH"));
    assert!(deck.contains("*BOUNDARY\nAXIS, 1, 1\nBOTTOM, 2, 2\nPUNCH, 1, 1\nSPRTOP, 1, 2\n"));
    let (s0, s1) = (n0 + 2 * np + 3, n0 + 2 * np + 4);
    assert!(deck.contains(&format!(
        "*ELEMENT, TYPE=CAX4, ELSET=ESPRING\n{}, {reference}, {}, {s1}, {s0}\n",
        mesh.elements.len() + np + 1,
        reference + 1
    )));
    // the spring's modulus: 10 N/mm over the first face's annulus, 1 mm long
    let r1 = o.punch_radius / np as f64;
    let e = force::spring_modulus(force::SPRING_STIFFNESS, o.punch_r_min, r1);
    let k = e * std::f64::consts::PI * (r1 * r1 - o.punch_r_min * o.punch_r_min);
    assert!((k - 10.0).abs() < 1e-9, "{k}");
    // the soft start: the first increment 1e-3 of the step, *VISCO for the viscous law
    let dt = 1.0 / 30.0;
    assert!(deck.contains(&format!(
        "*VISCO, CETOL=1.0\n{:.12e}, {:.12e}, {:.12e}, {dt:.12e}\n",
        dt * 1e-3,
        3.0,
        dt * 1e-7
    )));
    assert!(deck.contains("*NODE PRINT, NSET=REF, TIME POINTS=TP\nU\n"));
    // a depth-controlled segment is refused
    let mixed =
        indentify_contact::LoadHistory::from_segments(&[indentify_contact::HistorySegment {
            duration: 1.0,
            depth: Some(0.01),
            force: None,
            steps: 2,
        }])
        .unwrap();
    assert!(force::deck("t", &mesh, &punch, &m, &mixed, &o).is_err());
    assert_eq!(force::load_stem("r1", 0.1, true), "r1-mu0.1-nlgeom-load");
}

/// The deck of the R2 runs under `NLGEOM` (docs/validation-load-control.md §11):
/// Norton-Hoff as CalculiX's `*PLASTIC` + `*CREEP`, Coulomb friction, and the loading and
/// the rest as two `NLGEOM` steps, the amplitude and time points in total time, the soft
/// start in the first step only.
#[test]
fn force_deck_splits_the_load_under_nlgeom_with_norton_hoff_and_friction() {
    let mesh = cylinder_rz(2.0, 3, 2, 1.3);
    let punch = cone68();
    let m = Material::norton_hoff(1e5, 0.3, 1500.0, 5.0, 500.0);
    let o = DeckOptions {
        punch_segments: 4,
        nlgeom: true,
        split_load: true,
        friction: 0.1,
        ..DeckOptions::default()
    };
    let history = force::force_history(500.0).unwrap();
    let deck = force::deck("t", &mesh, &punch, &m, &history, &o).unwrap();
    // CalculiX's finite-strain Norton-Hoff: A = K^-m, n = m, the yield stress as *PLASTIC
    let a = 1500f64.powf(-5.0);
    assert!(deck.contains(&format!(
        "*ELASTIC\n1e5, 0.3\n*PLASTIC\n5e2, 0.0\n*CREEP, LAW=NORTON\n{a:.12e}, 5, 0.0\n"
    )));
    assert!(!deck.contains("*USER MATERIAL"));
    assert!(deck.contains("*FRICTION\n0.1, 1e8\n"));
    assert!(deck.contains("*AMPLITUDE, NAME=FORCE, TIME=TOTAL TIME\n"));
    assert!(deck.contains("*TIME POINTS, NAME=TP, TIME=TOTAL TIME\n"));
    // two NLGEOM steps: the ramp (1 s, the soft start) and the hold with the unloading (2 s)
    let dt = 1.0 / 30.0;
    let steps: Vec<&str> = deck.split("*STEP, NLGEOM").skip(1).collect();
    assert_eq!(steps.len(), 2);
    assert!(steps[0].contains(&format!(
        "*VISCO, CETOL=1.0\n{:.12e}, {:.12e}, {:.12e}, {dt:.12e}\n",
        dt * 1e-3,
        1.0,
        dt * 1e-7
    )));
    assert!(steps[1].contains(&format!(
        "*VISCO, CETOL=1.0\n{dt:.12e}, {:.12e}, {:.12e}, {dt:.12e}\n",
        2.0,
        dt * 1e-7
    )));
    for step in steps {
        assert!(step.contains("*CLOAD, AMPLITUDE=FORCE\n"));
        assert!(step.contains("*NODE PRINT, NSET=REF, TIME POINTS=TP\nU\n"));
    }
    assert_eq!(
        force::load_stem("r2-sy0", 0.1, true),
        "r2-sy0-mu0.1-nlgeom-load"
    );
}

/// The deck of the R2 runs with our own finite-strain law inside CalculiX
/// (`--drive force --elastic hencky-umat --kinematics nlgeom --split-load`,
/// docs/validation-load-control.md §11): the user material `USERHENCKY` with Norton-Hoff's
/// `E, nu, K, m, sY` in place of CalculiX's `*PLASTIC` and `*CREEP`, everything else the
/// load-controlled deck (the tie, the force, the spring, the split steps, the soft start);
/// the files' stem carries `-hencky`; a J2 material is refused (the user material has no
/// hardening).
#[test]
fn force_deck_runs_our_finite_strain_law_as_the_user_material() {
    let mesh = cylinder_rz(2.0, 3, 2, 1.3);
    let punch = cone68();
    let m = Material::norton_hoff(1e5, 0.3, 1500.0, 5.0, 500.0);
    let o = DeckOptions {
        punch_segments: 4,
        nlgeom: true,
        split_load: true,
        friction: 0.1,
        finite_elastic: FiniteElastic::HenckyUmat,
        ..DeckOptions::default()
    };
    let history = force::force_history(500.0).unwrap();
    let deck = force::deck("t", &mesh, &punch, &m, &history, &o).unwrap();
    // our law's parameters back from CalculiX's creep constants: E, nu, K, m, sY
    let card = deck
        .split("*MATERIAL, NAME=USERHENCKY\n*USER MATERIAL, CONSTANTS=5\n")
        .nth(1)
        .expect("the user material");
    let v: Vec<f64> = card
        .lines()
        .next()
        .unwrap()
        .split(',')
        .map(|x| x.trim().parse().unwrap())
        .collect();
    let expected = [1e5, 0.3, 1500.0, 5.0, 500.0];
    for (a, b) in v.iter().zip(expected) {
        assert!((a / b - 1.0).abs() < 1e-12, "{v:?}");
    }
    assert_eq!(v.len(), 5);
    assert!(card.contains("*DEPVAR\n6\n*SOLID SECTION, ELSET=ESPEC, MATERIAL=USERHENCKY\n"));
    assert!(!deck.contains("*PLASTIC") && !deck.contains("*CREEP"));
    // the rest is the load-controlled deck of CalculiX's own law, card for card
    let own = force::deck(
        "t",
        &mesh,
        &punch,
        &m,
        &history,
        &DeckOptions {
            finite_elastic: FiniteElastic::NeoHooke,
            ..o
        },
    )
    .unwrap();
    let after = |d: &str| {
        d.split("*MATERIAL, NAME=RIGID\n")
            .nth(1)
            .unwrap()
            .to_string()
    };
    assert_eq!(after(&deck), after(&own));
    assert!(after(&deck).contains("*FRICTION\n0.1, 1e8\n"));
    assert_eq!(deck.matches("*STEP, NLGEOM").count(), 2);
    assert_eq!(deck.matches("*VISCO, CETOL=1.0\n").count(), 2);
    assert_eq!(deck.matches("*CLOAD, AMPLITUDE=FORCE\n").count(), 2);
    // small strain keeps CalculiX's additive model: the user material is for NLGEOM
    let small = force::deck(
        "t",
        &mesh,
        &punch,
        &m,
        &history,
        &DeckOptions { nlgeom: false, ..o },
    )
    .unwrap();
    assert!(!small.contains("USERHENCKY") && small.contains("ANISO_PLAS_SPEC"));
    // the stems
    assert_eq!(
        force::material_load_stem("r2", 0.1, true, FiniteElastic::HenckyUmat, &m),
        "r2-mu0.1-nlgeom-hencky-load"
    );
    assert_eq!(
        force::material_load_stem("r2", 0.0, false, FiniteElastic::HenckyUmat, &m),
        "r2-load"
    );
    assert_eq!(
        force::material_load_stem("r2-sy0", 0.0, true, FiniteElastic::NeoHooke, &m),
        force::load_stem("r2-sy0", 0.0, true)
    );
    // a J2 material under the user material is refused, naming the reason
    let j2 = calculix::j2_case("r2-j2-linear").unwrap().material();
    let e = force::deck("t", &mesh, &punch, &j2, &history, &o).unwrap_err();
    assert!(e.to_string().contains("no hardening"), "{e}");
}

#[test]
fn dat_parser_reads_the_reference_depth_and_the_spring_force() {
    let dat = "\n displacements (vx,vy,vz) for set REF and time  0.1000000E+01\n\n      \
               1343  0.000000E+00 -9.986754E-02  0.000000E+00\n\n total force (fx,fy,fz) \
               for set SPRTOP and time  0.1000000E+01\n\n       -7.3E-06  5.0E-03 -5.2E-18\n";
    let raw = force::parse_dat(dat).unwrap();
    assert_eq!(raw.len(), 1);
    let (t, h, fs) = raw[0];
    assert_eq!(t, 1.0);
    assert_eq!(h, 9.986754e-2);
    assert!((fs - 0.9).abs() < 1e-12, "{fs}");
    let corners = [(0.0, 0.0), (1.0, 360.0)];
    let pts = force::points(&raw, &corners);
    assert_eq!(pts[0].p, 360.0);
    assert!((pts[0].f_contact - 359.1).abs() < 1e-9);
    let csv = force::points_csv(&pts);
    assert_eq!(force::read_points_csv(&csv).unwrap(), pts);
    // a displacement without its spring force is an error, not a silent curve
    let half = dat.split(" total force").next().unwrap();
    assert!(force::parse_dat(half).is_err());
}

/// One committed run this test recomputes, with the bounds it must keep
/// (docs/validation-load-control.md §11, each a little above what was measured).
struct Committed {
    /// The case of `calculix::CASES`.
    name: &'static str,
    /// Coulomb friction coefficient.
    mu: f64,
    /// `NLGEOM` (ours: `kinematics=Finite`).
    nlgeom: bool,
    /// CalculiX's material under `NLGEOM`: its own laws, or ours as its user material
    /// (`--elastic hencky-umat`, the stems `*-hencky-load`).
    elastic: FiniteElastic,
    /// Bound on `|h_ours - h_ccx| / h_max` over the whole history.
    worst: f64,
    /// Bound on `|h_ours / h_ccx - 1|` at 1, 2 and 3 s.
    at: f64,
    /// Bound on `|c_ours / c_ccx - 1|` of the creep over the hold, `c = h(2 s) - h(1 s)`
    /// (`None` for the elastic law, which does not creep: both codes then hold the depth
    /// to 1e-6 of h_max).
    creep: Option<f64>,
}

const fn run(
    name: &'static str,
    mu: f64,
    nlgeom: bool,
    (worst, at): (f64, f64),
    creep: Option<f64>,
) -> Committed {
    Committed {
        name,
        mu,
        nlgeom,
        elastic: FiniteElastic::NeoHooke,
        worst,
        at,
        creep,
    }
}

/// A committed run with our law as CalculiX's user material (`--elastic hencky-umat`).
const fn hencky(
    name: &'static str,
    mu: f64,
    (worst, at): (f64, f64),
    creep: Option<f64>,
) -> Committed {
    Committed {
        elastic: FiniteElastic::HenckyUmat,
        ..run(name, mu, true, (worst, at), creep)
    }
}

/// The committed runs: the first step, with a few contact nodes, differs most under small
/// strain; under `NLGEOM` the elastic laws differ, Hencky's against CalculiX's neo-Hooke
/// solid (R0, R1: 2-3% in depth, with Coulomb friction, mu 0.1, as without) or Simo's
/// elasticity with multiplicative flow (R2: 0.2-0.7% in depth, up to 1.1% of h_max in
/// the ramp, 0.6-2.1% in the creep over the hold); with our law as CalculiX's user
/// material (`hencky`) R2 agrees as under small strain (0.02-0.08% in depth, 0.02-0.26% in
/// the creep, 0.29-0.64% of h_max at the first steps).
const COMMITTED: [Committed; 20] = [
    run("r0", 0.0, false, (0.01, 0.004), None),
    run("r1", 0.0, false, (0.01, 0.004), Some(0.005)),
    run("r0", 0.1, false, (0.01, 0.004), None),
    run("r1", 0.1, false, (0.01, 0.004), Some(0.005)),
    run("r0", 0.0, true, (0.035, 0.035), None),
    run("r1", 0.0, true, (0.035, 0.035), Some(0.005)),
    run("r0", 0.1, true, (0.035, 0.035), None),
    run("r1", 0.1, true, (0.035, 0.035), Some(0.006)),
    run("r2", 0.0, false, (0.01, 0.004), Some(0.005)),
    run("r2", 0.1, false, (0.0075, 0.001), Some(0.004)),
    run("r2-sy0", 0.0, false, (0.0055, 0.0005), Some(0.001)),
    run("r2-sy0", 0.1, false, (0.009, 0.001), Some(0.002)),
    run("r2", 0.0, true, (0.011, 0.009), Some(0.01)),
    run("r2", 0.1, true, (0.014, 0.009), Some(0.008)),
    run("r2-sy0", 0.0, true, (0.0085, 0.006), Some(0.015)),
    run("r2-sy0", 0.1, true, (0.009, 0.008), Some(0.027)),
    hencky("r2", 0.0, (0.0083, 0.001), Some(0.00065)),
    hencky("r2", 0.1, (0.0082, 0.0006), Some(0.00025)),
    hencky("r2-sy0", 0.0, (0.0038, 0.0011), Some(0.0034)),
    hencky("r2-sy0", 0.1, (0.0073, 0.0007), Some(0.002)),
];

#[test]
fn committed_load_controlled_depths_are_ours_and_near_calculix() {
    let dir = root().join("validation/calculix");
    for Committed {
        name,
        mu,
        nlgeom,
        elastic,
        worst: bound,
        at: at_bound,
        creep,
    } in COMMITTED
    {
        let case = calculix::CASES.iter().find(|c| c.name == name).unwrap();
        let material = calculix::load(&root(), case).unwrap().material;
        let stem = force::material_load_stem(name, mu, nlgeom, elastic, &material);
        let read = |file: String| {
            std::fs::read_to_string(dir.join(&file))
                .unwrap_or_else(|e| panic!("{file}: {e} (run cargo xtask calculix --drive force)"))
        };
        let ccx = force::read_points_csv(&read(format!("{stem}.csv"))).unwrap();
        let committed = force::read_ours_csv(&read(format!("{stem}-ours.csv"))).unwrap();
        // CalculiX reached the end of the history: ramp, hold, unloading
        assert_eq!(ccx.len(), 90, "{stem}: {} points", ccx.len());
        assert!((ccx[89].t - 3.0).abs() < 1e-6, "{stem}");
        let ours = force::ours(&root(), case, mu, nlgeom, &ccx).unwrap();
        assert_eq!(ours.len(), committed.len(), "{stem}");
        let h_max = ccx.iter().map(|p| p.h).fold(0.0, f64::max);
        for (a, b) in ours.iter().zip(&committed) {
            assert!((a.0 - b.0).abs() < 1e-6, "{stem}: t {} vs {}", a.0, b.0);
            // the same depth as committed: our solver did not move
            assert!(
                (a.1 - b.1).abs() < 1e-6 * h_max,
                "{stem}: at t = {} our depth {} differs from the committed {}",
                a.0,
                a.1,
                b.1
            );
        }
        let c = force::compare(&ccx, &ours);
        println!(
            "{stem}: worst |dh|/h_max {:.3e} at t = {} s, at 1/2/3 s {:?}, spring share {:.2e}",
            c.worst.0, c.worst.1, c.at, c.spring_share
        );
        assert_eq!(c.at.len(), 3, "{stem}");
        for &(t, o, x) in &c.at {
            assert!(
                (o / x - 1.0).abs() < at_bound,
                "{stem}: at t = {t} s ours {o} mm, CalculiX {x} mm (bound {at_bound})"
            );
        }
        assert!(
            c.worst.0 < bound,
            "{stem}: worst |h_ours - h_ccx| / h_max = {} at t = {} s (bound {bound})",
            c.worst.0,
            c.worst.1
        );
        // the creep over the hold, the observable of the viscous laws' fits
        let (o, x) = (c.at[1].1 - c.at[0].1, c.at[1].2 - c.at[0].2);
        match creep {
            Some(b) => assert!(
                x > 0.05 * h_max && (o / x - 1.0).abs() < b,
                "{stem}: creep over the hold ours {o} mm, CalculiX {x} mm (bound {b})"
            ),
            None => assert!(
                o.abs() < 1e-6 * h_max && x.abs() < 1e-6 * h_max,
                "{stem}: the elastic depth moved over the hold: ours {o} mm, CalculiX {x} mm"
            ),
        }
    }
}
