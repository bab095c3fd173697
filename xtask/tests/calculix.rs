//! The CalculiX deck generator and `.dat` parser (without `ccx`): the materials against our
//! laws' own flow rules, the deck's mesh, surfaces and amplitude, the contact formulation
//! and the punch kept off the axis, the force parser, our side of every run (friction and
//! finite strain through `--set`, also both together) and the comparison table.

use indentify_contact::{ContactKind, Kinematics, Punch, Schedule};
use indentify_laws::{Law, Maxwell, NortonHoff, Vec4};
use indentify_testkit::{cone68, cylinder_rz, depth_lhu, workspace_root as root};
use xtask::calculix::{self, ContactType, DeckOptions, Material};

/// CalculiX's creep rate in uniaxial stress: `eps_dot_zz = A <sigma - r0>^n` (the
/// equivalent rate equals the axial one in uniaxial stress).
fn ccx_uniaxial_rate(m: &Material, sigma: f64) -> f64 {
    match *m {
        Material::Viscoplastic { a, n, sy, .. } => a * (sigma - sy).max(0.0).powf(n),
        Material::Elastic { .. } | Material::Plastic { .. } => 0.0,
    }
}

#[test]
fn creep_constants_reproduce_our_flow_rules() {
    // our laws' flow g(sigma) in uniaxial stress along z (Mandel [rr, zz, tt, sqrt2 rz])
    for sigma in [50.0, 700.0, 1900.0] {
        let s = Vec4([0.0, sigma, 0.0, 0.0]);
        let c = [20000.0, 0.3, 30000.0];
        let ours = Maxwell.flow(&c, &s).0[1];
        let m = Material::from_law("maxwell", &c).unwrap();
        let rel = ccx_uniaxial_rate(&m, sigma) / ours - 1.0;
        assert!(rel.abs() < 1e-12, "Maxwell at {sigma} MPa: {rel}");
        for sy in [0.0, 500.0] {
            let c = [1e5, 0.3, 1500.0, 5.0, sy];
            let ours = NortonHoff.flow(&c, &s).0[1];
            let m = Material::from_law("norton-hoff", &c).unwrap();
            let theirs = ccx_uniaxial_rate(&m, sigma);
            if sigma <= sy {
                assert_eq!(ours, 0.0);
                assert_eq!(theirs, 0.0);
            } else {
                let rel = theirs / ours - 1.0;
                assert!(
                    rel.abs() < 1e-12,
                    "Norton-Hoff sY = {sy} at {sigma} MPa: {rel}"
                );
            }
        }
    }
    assert!(Material::from_law("norton-hoff", &[1.0, 0.3]).is_err());
}

fn small_problem() -> (indentify_mesh::Mesh, Schedule) {
    let mesh = cylinder_rz(2.0, 3, 2, 1.3);
    let schedule = depth_lhu(0.1, 0.0, 4);
    (mesh, schedule)
}

#[test]
fn deck_holds_our_mesh_node_for_node() {
    let (mesh, schedule) = small_problem();
    let punch = cone68();
    let m = Material::norton_hoff(1e5, 0.3, 1500.0, 5.0, 500.0);
    let o = DeckOptions {
        punch_segments: 4,
        ..DeckOptions::default()
    };
    let deck = calculix::deck("test", &mesh, &punch, &m, &schedule, &o).unwrap();
    // every node of ours, numbered from 1, with its coordinates
    for (i, p) in mesh.nodes.iter().enumerate() {
        let line = format!("{}, {:.12e}, {:.12e}, 0.0", i + 1, p[0], p[1]);
        assert!(deck.contains(&line), "node {i} missing: {line}");
    }
    // every element with our node order (CAX8 and our Q8 share it)
    for (e, el) in mesh.elements.iter().enumerate() {
        let ids: Vec<String> = el.iter().map(|n| (n + 1).to_string()).collect();
        assert!(deck.contains(&format!("\n{}, {}\n", e + 1, ids.join(", "))));
    }
    // the top surface: one face per element column, on z = 0
    let faces = calculix::top_faces(&mesh);
    assert_eq!(faces.len(), 3);
    for (e, k) in &faces {
        let el = mesh.elements[*e];
        assert_eq!(mesh.nodes[el[*k]][1], 0.0);
        assert_eq!(mesh.nodes[el[(*k + 1) % 4]][1], 0.0);
    }
    // the small-strain viscoplastic material: A = K^-m, n = m, r0 = sY
    assert!(deck.contains("*MATERIAL, NAME=ANISO_PLAS_SPEC"));
    assert!(deck.contains(&format!(
        "{:e}, 0.0, 0.0, {:.12e}, 5, 0.0",
        500.0,
        1500f64.powf(-5.0)
    )));
    // the trapezoid's corners as amplitude, the punch driven to -h_max
    let amp = deck.split("*AMPLITUDE, NAME=DEPTH\n").nth(1).unwrap();
    let rows: Vec<&str> = amp.lines().take_while(|l| !l.starts_with('*')).collect();
    assert_eq!(rows.len(), 4, "{rows:?}");
    assert!(deck.contains("PUNCH, 2, 2, -1.000000000000e-1"));
    assert!(!deck.contains("NLGEOM"));
    assert!(!deck.contains("*FRICTION"));
    // finite strain and friction variants
    let nl = DeckOptions {
        nlgeom: true,
        friction: 0.2,
        ..o
    };
    let deck = calculix::deck("test", &mesh, &punch, &m, &schedule, &nl).unwrap();
    assert!(deck.contains("*STEP, NLGEOM"));
    assert!(deck.contains("*CREEP, LAW=NORTON") && deck.contains("*PLASTIC"));
    assert!(deck.contains("*FRICTION\n0.2, "));
    // a sphere is refused with a message naming it
    let e = calculix::deck(
        "t",
        &mesh,
        &Punch::Sphere { radius: 1.0 },
        &m,
        &schedule,
        &o,
    );
    assert!(e.unwrap_err().to_string().contains("cone"));
}

#[test]
fn dat_parser_reads_the_punch_force_of_the_full_circle() {
    let dat = "\n total force (fx,fy,fz) for set PUNCH and time  0.5000000E+00\n\n        \
               1.0E-02 -5.000000E-01  0.0E+00\n\n total force (fx,fy,fz) for set PUNCH and time  \
               0.1000000E+01\n\n        2.0E-02 -2.000000E+00  0.0E+00\n";
    let c = calculix::parse_dat(dat).unwrap();
    assert_eq!(c, vec![(0.5, 90.0), (1.0, 360.0)]);
    assert_eq!(calculix::at(&c, 0.75), Some(225.0));
    assert_eq!(calculix::at(&c, 2.0), None);
    let csv = calculix::curve_csv(&c);
    assert_eq!(calculix::read_curve_csv(&csv).unwrap(), c);
    assert!(calculix::parse_dat(" total force (fx,fy,fz) for set PUNCH and time 1.0\n").is_err());
}

#[test]
fn node_to_surface_keeps_the_punch_and_the_slave_off_the_axis() {
    let (mesh, schedule) = small_problem();
    let punch = cone68();
    let m = Material::maxwell(2e4, 0.3, 3e4);
    let o = DeckOptions {
        punch_segments: 4,
        ..DeckOptions::default()
    };
    assert_eq!(o.contact, ContactType::NodeToSurface);
    let deck = calculix::deck("test", &mesh, &punch, &m, &schedule, &o).unwrap();
    assert!(deck.contains("*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE\n"));
    // the flank's first node pair at r = 1e-4 mm on the cone (z = r cot 68 deg), not on the axis
    let cot = 1.0 / 68f64.to_radians().tan();
    let n0 = mesh.nodes.len();
    let first = format!("\n{}, {:.12e}, {:.12e}, 0.0\n", n0 + 1, 1e-4, 1e-4 * cot);
    assert!(deck.contains(&first), "{first}");
    // the slave surface: every top face but the one on the axis (3 columns -> 2 faces)
    let all = calculix::top_faces(&mesh);
    let slave = calculix::slave_faces(&mesh, ContactType::NodeToSurface);
    assert_eq!((all.len(), slave.len()), (3, 2));
    let (e_axis, k_axis) = all
        .iter()
        .copied()
        .find(|&(e, k)| {
            let el = mesh.elements[e];
            mesh.nodes[el[k]][0] == 0.0 || mesh.nodes[el[(k + 1) % 4]][0] == 0.0
        })
        .unwrap();
    assert!(!slave.contains(&(e_axis, k_axis)));
    let surface = deck
        .split("*SURFACE, NAME=STOP, TYPE=ELEMENT\n")
        .nth(1)
        .unwrap();
    let rows: Vec<&str> = surface
        .lines()
        .take_while(|l| !l.starts_with('*'))
        .collect();
    assert_eq!(rows.len(), 2);
    assert!(!rows.contains(&format!("{}, S{}", e_axis + 1, k_axis + 1).as_str()));
    // surface-to-surface keeps every face
    let s2s = DeckOptions {
        contact: ContactType::SurfaceToSurface,
        ..o
    };
    let deck = calculix::deck("test", &mesh, &punch, &m, &schedule, &s2s).unwrap();
    assert!(deck.contains("TYPE=SURFACE TO SURFACE\n"));
    assert_eq!(
        calculix::slave_faces(&mesh, ContactType::SurfaceToSurface),
        all
    );
    // a flank starting beyond its first face is refused, naming the radius
    let bad = DeckOptions {
        punch_r_min: 1.0,
        ..o
    };
    let e = calculix::deck("t", &mesh, &punch, &m, &schedule, &bad).unwrap_err();
    assert!(e.to_string().contains("r = 1 mm"), "{e}");
    assert_eq!(
        ContactType::from_name("surface-to-surface").unwrap(),
        ContactType::SurfaceToSurface
    );
    let e = ContactType::from_name("mortar").unwrap_err().to_string();
    assert!(e.contains("--contact") && e.contains("mortar"), "{e}");
}

#[test]
fn our_runs_are_the_configurations_with_friction_and_finite_strain() {
    let r2 = calculix::CASES.iter().find(|c| c.name == "r2-sy0").unwrap();
    let sets = calculix::our_sets(r2, 0.1, true);
    assert_eq!(
        sets,
        [
            "contact=Normal(friction: 0.1)",
            "kinematics=Finite",
            "law.sY=0"
        ]
    );
    let source = indentify_study::source::ConfigSource::Path(root().join(r2.example));
    // finite strain with friction: the configuration loads with both
    let cfg = source.load(&sets).unwrap();
    assert_eq!(cfg.contact, ContactKind::NormalFriction { friction: 0.1 });
    assert_eq!(cfg.kinematics, Kinematics::Finite);
    let cfg = source.load(&calculix::our_sets(r2, 0.1, false)).unwrap();
    assert_eq!(cfg.contact, ContactKind::NormalFriction { friction: 0.1 });
    assert_eq!(cfg.kinematics, Kinematics::Small);
    let cfg = source.load(&calculix::our_sets(r2, 0.0, false)).unwrap();
    assert_eq!(cfg.contact, ContactKind::Normal);
    assert_eq!(cfg.kinematics, Kinematics::Small);
    // the stems name every run
    assert_eq!(calculix::stem("r2-sy0", 0.1, true), "r2-sy0-mu0.1-nlgeom");
    assert_eq!(calculix::stem("r1", 0.0, false), "r1");
}

#[test]
fn table_rows_compare_ours_or_the_frictionless_reference() {
    let ccx = vec![
        (0.0, 0.0),
        (0.5, 100.0),
        (1.0, 400.0),
        (1.5, 390.0),
        (2.0, 380.0),
    ];
    let ours: Vec<(f64, f64)> = ccx.iter().map(|&(t, f)| (t, 1.01 * f)).collect();
    let row = calculix::table_row("r1", &ccx, Some(&ours), None, 2.0, "");
    assert_eq!(
        row,
        "| r1 | 101.00 / 100.00 N: **+1.00%** | 404.00 / 400.00 N: **+1.00%** | \
         393.90 / 390.00 N: **+1.00%** | 383.80 / 380.00 N: **+1.00%** | end |  |"
    );
    // no curve of ours: CalculiX against its frictionless run; a run that stopped at 1.2 s
    let stopped: Vec<(f64, f64)> = ccx[..3]
        .iter()
        .copied()
        .chain([(1.2, 396.0)])
        .map(|(t, f)| (t, 1.02 * f))
        .collect();
    let row = calculix::table_row(
        "r1-mu0.1-nlgeom",
        &stopped,
        None,
        Some(&ccx),
        3.0,
        "ours: refused",
    );
    assert!(
        row.starts_with("| r1-mu0.1-nlgeom | ccx 102.00 N (+2.00% vs mu = 0) | ccx 408.00 N (+2.00% vs mu = 0) | - | - | t = 1.200 s | ours: refused |"),
        "{row}"
    );
}

#[test]
fn split_load_writes_the_loading_and_the_rest_as_two_steps_in_total_time() {
    let (mesh, schedule) = small_problem();
    let punch = cone68();
    let m = Material::norton_hoff(1e5, 0.3, 1500.0, 5.0, 0.0);
    let one = DeckOptions {
        punch_segments: 4,
        nlgeom: true,
        ..DeckOptions::default()
    };
    let deck = calculix::deck("t", &mesh, &punch, &m, &schedule, &one).unwrap();
    assert_eq!(deck.matches("*STEP, NLGEOM").count(), 1);
    assert!(!deck.contains("TOTAL TIME"));
    // dt = 0.25 s over the whole 3 s history
    assert!(deck.contains("\n2.500000000000e-1, 3.000000000000e0, "));
    let two = DeckOptions {
        split_load: true,
        ..one
    };
    let deck = calculix::deck("t", &mesh, &punch, &m, &schedule, &two).unwrap();
    assert_eq!(deck.matches("*STEP, NLGEOM").count(), 2);
    assert_eq!(deck.matches("*END STEP").count(), 2);
    assert!(deck.contains("*AMPLITUDE, NAME=DEPTH, TIME=TOTAL TIME\n"));
    assert!(deck.contains("*TIME POINTS, NAME=TP, TIME=TOTAL TIME\n"));
    // the loading segment (1 s), then the hold and the unloading (2 s)
    let first = deck
        .find("\n2.500000000000e-1, 1.000000000000e0, ")
        .unwrap();
    let second = deck
        .find("\n2.500000000000e-1, 2.000000000000e0, ")
        .unwrap();
    assert!(first < second);
    // the loading's increments divided (--load-substeps 5), the rest's kept, the minimum
    // (dt 1e-4) kept
    let sub = DeckOptions {
        load_substeps: 5,
        ..two
    };
    let deck = calculix::deck("t", &mesh, &punch, &m, &schedule, &sub).unwrap();
    assert!(
        deck.contains(
            "\n5.000000000000e-2, 1.000000000000e0, 2.500000000000e-5, 5.000000000000e-2\n"
        )
    );
    assert!(
        deck.contains(
            "\n2.500000000000e-1, 2.000000000000e0, 2.500000000000e-5, 2.500000000000e-1\n"
        )
    );
    let zero = DeckOptions {
        load_substeps: 0,
        ..two
    };
    let e = calculix::deck("t", &mesh, &punch, &m, &schedule, &zero).unwrap_err();
    assert!(e.to_string().contains("load_substeps"), "{e}");
}

#[test]
fn mooney_rivlin_deck_states_hencky_s_shear_modulus_in_both_invariants() {
    let (mesh, schedule) = small_problem();
    let punch = cone68();
    let m = Material::Elastic { e: 2e4, nu: 0.3 };
    let o = DeckOptions {
        punch_segments: 4,
        nlgeom: true,
        finite_elastic: calculix::FiniteElastic::MooneyRivlin,
        ..DeckOptions::default()
    };
    let deck = calculix::deck("t", &mesh, &punch, &m, &schedule, &o).unwrap();
    let card = deck
        .split("*HYPERELASTIC, MOONEY-RIVLIN\n")
        .nth(1)
        .and_then(|rest| rest.lines().next())
        .expect("a Mooney-Rivlin card");
    let v: Vec<f64> = card.split(',').map(|x| x.trim().parse().unwrap()).collect();
    let mu = 2e4 / (2.0 * 1.3);
    let kappa = 2e4 / (3.0 * (1.0 - 0.6));
    // C10 = C01 = mu/4: the initial shear modulus 2 (C10 + C01) = mu
    assert!((v[0] - mu / 4.0).abs() < 1e-9 * mu && (v[1] - mu / 4.0).abs() < 1e-9 * mu);
    assert!((v[2] - 2.0 / kappa).abs() < 1e-12 / kappa);
    assert!(!deck.contains("NEO HOOKE"));
    // the default stays neo-Hooke, and small strain stays *ELASTIC
    let nh = DeckOptions {
        finite_elastic: calculix::FiniteElastic::NeoHooke,
        ..o
    };
    let deck = calculix::deck("t", &mesh, &punch, &m, &schedule, &nh).unwrap();
    assert!(deck.contains("*HYPERELASTIC, NEO HOOKE\n"));
    assert!(calculix::FiniteElastic::from_name("ogden").is_err());
}

#[test]
fn hencky_umat_constants_are_our_laws_parameters() {
    // back from CalculiX's creep constants to our parameters, to round-off
    let close = |a: &[f64], b: &[f64]| {
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(x, y)| (x - y).abs() <= 1e-14 * y.abs().max(1e-300))
    };
    let maxwell = Material::from_law("maxwell", &[2e4, 0.3, 3e4]).unwrap();
    let c = calculix::hencky_umat_constants(&maxwell);
    assert!(close(&c, &[2e4, 0.3, 3e4]), "{c:?}");
    let nh = Material::from_law("norton-hoff", &[1e5, 0.3, 1500.0, 5.0, 500.0]).unwrap();
    let c = calculix::hencky_umat_constants(&nh);
    assert!(close(&c, &[1e5, 0.3, 1500.0, 5.0, 500.0]), "{c:?}");
    // sY = 0 with m = 1 is Maxwell's flow in Norton-Hoff's form: written as Maxwell
    // (eta = 2 K / 3), the same law (umat/test_point.f checks both forms agree)
    let nh1 = Material::from_law("norton-hoff", &[1e5, 0.3, 1500.0, 1.0, 0.0]).unwrap();
    let c = calculix::hencky_umat_constants(&nh1);
    assert!(close(&c, &[1e5, 0.3, 1000.0]), "{c:?}");
    let el = Material::Elastic { e: 2e4, nu: 0.3 };
    assert_eq!(calculix::hencky_umat_constants(&el), vec![2e4, 0.3]);
}

#[test]
fn hencky_umat_deck_replaces_every_law_under_nlgeom_only() {
    let (mesh, schedule) = small_problem();
    let punch = cone68();
    let o = DeckOptions {
        punch_segments: 4,
        nlgeom: true,
        finite_elastic: calculix::FiniteElastic::HenckyUmat,
        ..DeckOptions::default()
    };
    let card = |deck: &str| -> Vec<f64> {
        let rest = deck
            .split("*MATERIAL, NAME=USERHENCKY\n")
            .nth(1)
            .expect("the user material");
        let mut lines = rest.lines();
        let head = lines.next().unwrap();
        let v: Vec<f64> = lines
            .next()
            .unwrap()
            .split(',')
            .map(|x| x.trim().parse().unwrap())
            .collect();
        assert_eq!(head, format!("*USER MATERIAL, CONSTANTS={}", v.len()));
        assert!(rest.contains("*DEPVAR\n6\n*SOLID SECTION, ELSET=ESPEC, MATERIAL=USERHENCKY\n"));
        v
    };
    let maxwell = Material::from_law("maxwell", &[2e4, 0.3, 3e4]).unwrap();
    let deck = calculix::deck("t", &mesh, &punch, &maxwell, &schedule, &o).unwrap();
    let v = card(&deck);
    assert_eq!(v.len(), 3);
    assert!((v[2] - 3e4).abs() < 1e-9, "{v:?}");
    assert!(!deck.contains("*CREEP") && deck.contains("*VISCO"));
    let elastic = Material::Elastic { e: 2e4, nu: 0.3 };
    let deck = calculix::deck("t", &mesh, &punch, &elastic, &schedule, &o).unwrap();
    assert_eq!(card(&deck), vec![2e4, 0.3]);
    assert!(!deck.contains("*HYPERELASTIC") && deck.contains("*STATIC"));
    // small strain keeps its materials
    let small = DeckOptions { nlgeom: false, ..o };
    let deck = calculix::deck("t", &mesh, &punch, &maxwell, &schedule, &small).unwrap();
    assert!(!deck.contains("USERHENCKY") && deck.contains("ANISO_PLAS_SPEC"));
    // the stems: every law gets -hencky, the hyperelastic suffixes only the elastic law
    let hu = calculix::FiniteElastic::from_name("hencky-umat").unwrap();
    assert_eq!(hu.suffix(), "-hencky");
    assert!(hu.applies_to(&maxwell) && hu.applies_to(&elastic));
    let mr = calculix::FiniteElastic::MooneyRivlin;
    assert!(mr.applies_to(&elastic) && !mr.applies_to(&maxwell));
    let e = calculix::FiniteElastic::from_name("hencky").unwrap_err();
    assert!(e.to_string().contains("hencky-umat"), "{e}");
}

#[test]
fn decks_only_run_names_the_hencky_umat_decks_and_a_missing_ccx_is_named() {
    let out = std::env::temp_dir().join(format!("indentify-umat-decks-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let o = calculix::RunOptions {
        root: root(),
        out: out.clone(),
        cases: vec!["r0".into(), "r1".into()],
        frictions: vec![0.0],
        kinematics: vec![true],
        deck: DeckOptions {
            finite_elastic: calculix::FiniteElastic::HenckyUmat,
            split_load: true,
            ..DeckOptions::default()
        },
        decks_only: true,
        reuse: false,
        no_ccx: false,
        ccx: "/nonexistent/ccx_hencky".into(),
    };
    calculix::run(&o).unwrap();
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["r0-nlgeom-hencky.inp", "r1-nlgeom-hencky.inp"]);
    let r1 = std::fs::read_to_string(out.join("r1-nlgeom-hencky.inp")).unwrap();
    assert!(r1.contains("*MATERIAL, NAME=USERHENCKY\n*USER MATERIAL, CONSTANTS=3\n"));
    // the executable of --ccx is the one started, and a missing one is named
    let e = calculix::run_ccx(&o.ccx, &out, "r1-nlgeom-hencky", &r1).unwrap_err();
    let text = format!("{e:#}");
    assert!(
        text.contains("/nonexistent/ccx_hencky") && text.contains("build.sh"),
        "{text}"
    );
    std::fs::remove_dir_all(&out).unwrap();
}
