//! Annotated template configurations: one per law, set to the reference problems R0-R2
//! (the files in `examples/` are exactly this output), and the template for a measured
//! record. `indentify init` prints them.

use std::path::{Path, PathBuf};

use serde_json::Value;

use indentify_contact::punch::AutoOptions;

use crate::config::{Config, DataSection, IdentifySection, ParamSetting, Reference, Specimen};

/// The annotated template of a reference problem.
pub fn template(reference: Reference) -> String {
    let law = match reference {
        Reference::R0Elastic => "elastic",
        Reference::R1Maxwell => "maxwell",
        Reference::R2NortonHoff => "norton-hoff",
    };
    annotated(
        &reference.config(),
        &[
            format!(
                "{} (examples/{}).",
                reference.title(),
                reference.example_file()
            ),
            format!(
                "indentify configuration written by `indentify init {law}`; \
                 run it with `indentify simulate FILE.ron` or `indentify identify FILE.ron`."
            ),
        ],
    )
}

/// The laws `indentify init` writes beyond the reference problems, by kind: J2 plasticity
/// with each hardening form (and with a Norton rate), and a Prony series; each a law text
/// the registry reads.
pub const LAW_TEMPLATES: &[(&str, &str)] = &[
    (
        "plastic-linear",
        "Plastic(E: 70000.0, nu: 0.3, sY: 300.0, hardening: Linear(H: 2000.0))",
    ),
    (
        "plastic-power",
        "Plastic(E: 70000.0, nu: 0.3, sY: 300.0, hardening: Power(n: 0.2))",
    ),
    (
        "plastic-voce",
        "Plastic(E: 70000.0, nu: 0.3, sY: 300.0, hardening: Voce(Q: 150.0, b: 40.0))",
    ),
    (
        "plastic-swift",
        "Plastic(E: 70000.0, nu: 0.3, sY: 300.0, hardening: Swift(eps0: 0.01, n: 0.2))",
    ),
    (
        "plastic-table",
        "Plastic(E: 70000.0, nu: 0.3, sY: 300.0, \
         hardening: Table(points: [(0.0, 300.0), (0.05, 360.0), (0.2, 420.0)]))",
    ),
    (
        "plastic-norton",
        "Plastic(E: 70000.0, nu: 0.3, sY: 300.0, hardening: Power(n: 0.2), \
         rate: Norton(K: 200.0, m: 3.0))",
    ),
    (
        "prony",
        "Prony(E: 3000.0, nu: 0.35, terms: [(g: 0.3, tau: 0.1), (g: 0.2, tau: 1.0)])",
    ),
];

/// The annotated template of the law `kind` of [`LAW_TEMPLATES`] on R1's specimen, cone and
/// history, every parameter but nu identified from its law value within the law's range.
///
/// # Errors
/// A kind not in [`LAW_TEMPLATES`] (listing them).
pub fn law_template(kind: &str) -> anyhow::Result<String> {
    let (_, text) = LAW_TEMPLATES
        .iter()
        .find(|(k, _)| *k == kind)
        .ok_or_else(|| {
            anyhow::anyhow!(
                "no template `{kind}`; templates: elastic, maxwell, norton-hoff, {}",
                LAW_TEMPLATES
                    .iter()
                    .map(|(k, _)| *k)
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })?;
    let law: crate::config::LawSpec = ron::from_str(text)?;
    let mut cfg = Reference::R1Maxwell.config();
    let mut id = IdentifySection::default();
    for (name, _) in law.named_params() {
        let setting = if name == "nu" {
            ParamSetting::Fixed { value: None }
        } else {
            ParamSetting::Free {
                start: None,
                lower: None,
                upper: None,
                scaling: None,
            }
        };
        id.params.insert(name.to_string(), setting);
    }
    let summary = law.entry().summary;
    cfg.law = law;
    cfg.identify = Some(id);
    Ok(annotated(
        &cfg,
        &[
            format!("R1's specimen, cone and history with {summary}."),
            format!(
                "indentify configuration written by `indentify init {kind}`; check it with \
                 `indentify check FILE.ron`; simulate and identify it like any other law."
            ),
        ],
    ))
}

/// What `init --data` knows of the record it writes a template for.
#[derive(Clone, Debug, PartialEq)]
pub struct DataTemplate {
    /// The path written into `data.file` (as given).
    pub file: String,
    /// The test of a multi-test file (from 1), if it has several.
    pub test: Option<usize>,
    /// The tests' names, when the file holds several.
    pub tests: Vec<String>,
    /// The punch, and where it comes from (`--tip`, the file's metadata, or assumed).
    pub punch: indentify_contact::Punch,
    /// Where the punch comes from, for the header.
    pub punch_source: String,
}

/// Parses a `--tip` value: `berkovich`, `vickers`, `cube-corner`, `sphere:R` (R in mm) or
/// `cone:DEG` (half-angle in degrees).
///
/// # Errors
/// Anything else, with the allowed forms.
pub fn parse_tip(text: &str) -> anyhow::Result<indentify_contact::Punch> {
    use indentify_contact::Punch;
    let t = text.trim().to_ascii_lowercase();
    let number = |v: &str, what: &str| -> anyhow::Result<f64> {
        match v.trim().parse::<f64>() {
            Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
            _ => anyhow::bail!("--tip `{text}`: `{v}` is not a {what} > 0"),
        }
    };
    let punch = match t.split_once(':') {
        None if t == "berkovich" => Punch::Berkovich { tip_radius: None },
        None if t == "vickers" => Punch::Vickers { tip_radius: None },
        None if t == "cube-corner" || t == "cubecorner" => Punch::CubeCorner { tip_radius: None },
        Some(("sphere", r)) => Punch::Sphere {
            radius: number(r, "radius in mm")?,
        },
        Some(("cone", a)) => Punch::Cone {
            half_angle_deg: number(a, "half-angle in degrees")?,
        },
        _ => anyhow::bail!(
            "--tip `{text}` is not a tip: expected berkovich, vickers, cube-corner, sphere:R (R \
             in mm, e.g. sphere:0.01) or cone:DEG (half-angle, e.g. cone:70.3)"
        ),
    };
    punch.validate()?;
    Ok(punch)
}

/// The punch a record's metadata states (`Berkovich`, `Vickers`, `cube corner`, a sphere
/// with its radius), if any.
pub fn tip_from_metadata(meta: &indentify_records::Meta) -> Option<indentify_contact::Punch> {
    use indentify_contact::Punch;
    let tip = meta.tip.as_deref().unwrap_or("").to_ascii_lowercase();
    if tip.contains("berkovich") {
        Some(Punch::Berkovich { tip_radius: None })
    } else if tip.contains("vickers") {
        Some(Punch::Vickers { tip_radius: None })
    } else if tip.contains("cube") {
        Some(Punch::CubeCorner { tip_radius: None })
    } else if tip.contains("spher") || tip.contains("ball") || meta.tip_radius.is_some() {
        meta.tip_radius
            .filter(|r| *r > 0.0)
            .map(|radius| Punch::Sphere { radius })
    } else {
        None
    }
}

/// The annotated template for a measured record with the law of `reference`: the automatic
/// specimen, the record's punch, 60 resampled points, every parameter but nu free within
/// ranges and stopping rules that work on real records (m > 1.1 for Norton-Hoff, where the
/// adjoint is defined; a relative decrease of 1e-4, since a real record's misfit does not
/// go to zero).
pub fn data_template(reference: Reference, d: &DataTemplate) -> String {
    data_template_with_guess(reference, d, None)
}

/// [`data_template`] with the law's start values from the record's Oliver-Pharr analysis
/// (`crate::first_guess`), its numbers and derivations in the header.
pub fn data_template_with_guess(
    reference: Reference,
    d: &DataTemplate,
    guess: Option<&crate::first_guess::FirstGuess>,
) -> String {
    let cfg = reference.config();
    let name = cfg.law.name().to_string();
    data_config(cfg, reference.identify_section(), d, guess, &name)
}

/// The law `init KIND --data` starts from for a kind of [`LAW_TEMPLATES`]: its template
/// law, except `prony`, which has one term (one hold determines one `(g, tau)`).
///
/// # Errors
/// A kind not in [`LAW_TEMPLATES`].
pub fn data_law(kind: &str) -> anyhow::Result<crate::config::LawSpec> {
    if kind == "prony" {
        return Ok(ron::from_str(
            "Prony(E: 3000.0, nu: 0.3, terms: [(g: 0.3, tau: 1.0)])",
        )?);
    }
    let (_, text) = LAW_TEMPLATES
        .iter()
        .find(|(k, _)| *k == kind)
        .ok_or_else(|| anyhow::anyhow!("no template `{kind}`"))?;
    Ok(ron::from_str(text)?)
}

/// [`data_template_with_guess`] for the law `law` of `init KIND --data` (a kind of
/// [`LAW_TEMPLATES`]): every parameter but nu free (`m` within [1.1, 30]).
pub fn data_template_law(
    kind: &str,
    law: crate::config::LawSpec,
    d: &DataTemplate,
    guess: Option<&crate::first_guess::FirstGuess>,
) -> String {
    let mut cfg = Reference::R2NortonHoff.config();
    let mut id = IdentifySection::default();
    for (name, _) in law.named_params() {
        id.params.insert(
            name.to_string(),
            ParamSetting::Free {
                start: None,
                lower: None,
                upper: None,
                scaling: None,
            },
        );
    }
    cfg.law = law;
    data_config(cfg, id, d, guess, kind)
}

fn data_config(
    mut cfg: Config,
    mut id: IdentifySection,
    d: &DataTemplate,
    guess: Option<&crate::first_guess::FirstGuess>,
    init_name: &str,
) -> String {
    if let Some(g) = guess {
        crate::first_guess::apply(&mut cfg.law, g);
    }
    cfg.specimen = Specimen::Auto {
        elements_in_contact: AutoOptions::default().elements_in_contact,
        size_factor: AutoOptions::default().size_factor,
        grading: AutoOptions::default().grading,
    };
    cfg.punch = d.punch.clone();
    cfg.history = None;
    // measured data: the physical model (Config::resolve_model_defaults), written out
    cfg.contact = indentify_contact::ContactKind::Normal;
    cfg.kinematics = indentify_contact::Kinematics::Finite;
    cfg.data = Some(DataSection {
        file: d.file.clone(),
        format: indentify_records::Format::Auto,
        test: d.test,
        drive: crate::config::Drive::Depth,
        preprocessing: indentify_records::Preprocessing {
            resample: Some(indentify_records::Resample {
                n: 60,
                ..indentify_records::Resample::default()
            }),
            ..indentify_records::Preprocessing::default()
        },
        substeps: crate::config::DEFAULT_SUBSTEPS,
    });
    for (name, setting) in id.params.iter_mut() {
        *setting = match name.as_str() {
            "nu" => ParamSetting::Fixed { value: Some(0.3) },
            "m" => ParamSetting::Free {
                start: None,
                lower: Some(1.1),
                upper: Some(30.0),
                scaling: None,
            },
            _ => ParamSetting::Free {
                start: None,
                lower: None,
                upper: None,
                scaling: None,
            },
        };
    }
    id.stop.relative_decrease_tol = 1e-4;
    cfg.identify = Some(id);
    let law = cfg.law.name();
    let file = &d.file;
    let mut header = vec![format!(
        "Identification of {law} parameters from the measured record `{file}`{}.",
        d.test.map_or(String::new(), |t| format!(", test {t}"))
    )];
    if d.tests.len() > 1 {
        header.push(format!(
            "The file holds {} tests ({}): data.test chooses one.",
            d.tests.len(),
            d.tests.join(", ")
        ));
    }
    header.push(format!("Punch: {}.", d.punch_source));
    if let Some(g) = guess {
        header.push(format!(
            "Start values from the record's {} (docs/analysis.md, First guesses):",
            crate::first_guess::describe(&g.op)
        ));
        header.extend(g.notes.iter().map(|n| format!("  {n}.")));
    }
    header.push(format!(
        "indentify configuration written by `indentify init {init_name} --data {file}`: check the \
         punch, the law's start values (the vendor's E_IT is a fair start for E) and nu, check \
         it with `indentify check FILE.ron`, run it with `indentify identify FILE.ron` \
         (docs/tutorial-real-data.md)."
    ));
    annotated(&cfg, &header)
}

/// A configuration as RON text with comments on every field (units, admissible ranges,
/// alternatives); `header` lines open the file. Parses back to `cfg` exactly.
pub fn annotated(cfg: &Config, header: &[String]) -> String {
    let mut out = String::new();
    for line in header {
        out.push_str(&format!("// {line}\n"));
    }
    out.push_str(
        "//\n\
         // Units: N, mm, s, MPa. Every field is required except `solver` and `identify`; an unknown or\n\
         // mistyped field is an error. Any scalar can be overridden on the command line by its\n\
         // dotted path, e.g. `--set law.E=25000 --set specimen.nr=10 --set history.segments.0.depth=0.2`.\n\
         (\n",
    );

    out.push_str(
        "    // The specimen, one of\n\
         \x20   //   Cylinder(radius, height, nr, nz, grading_r, grading_z): the cylinder\n\
         \x20   //     0 <= r <= radius, -height <= z <= 0 (the punch presses on z = 0) cut into nr x nz\n\
         \x20   //     8-node quadrilaterals whose sizes grow geometrically away from the axis (ratio\n\
         \x20   //     grading_r) and away from the top surface (ratio grading_z);\n\
         \x20   //   Auto(elements_in_contact: 12, size_factor: 48.0, grading: 1.5): sized from the punch\n\
         \x20   //     and the maximum depth a = contact-radius bound (geometric radius x 1.2): radius =\n\
         \x20   //     height = size_factor x a, a uniform core of elements_in_contact squares per side\n\
         \x20   //     over a, graded beyond (instrument scale: nm to mm indents alike).\n",
    );
    specimen_block(&mut out, cfg.specimen);
    out.push_str("    ),\n");

    out.push_str(
        "    // Rigid frictionless punch (lengths in mm, half-angles from the axis in degrees), one of\n\
         \x20   //   Cone(half_angle_deg: 68.0)                     half-angle in (0, 90); 70.3 = Berkovich-equivalent\n\
         \x20   //   Sphere(radius: 1.0)                            exact spherical profile, radius > 0\n\
         \x20   //   Flat(radius: 0.5)                              flat-ended cylinder, radius > 0\n\
         \x20   //   SpheroCone(radius: 1.0, half_angle_deg: 68.0)  spherical tip blended tangentially into a cone\n\
         \x20   //   Tabulated(r: [0.0, 1.0], z: [0.0, 0.4])        heights z above the tip at increasing radii r\n\
         \x20   //   Berkovich(), Vickers()                         area-equivalent cone of 70.3 deg (A = 24.5 h^2)\n\
         \x20   //   CubeCorner()                                   area-equivalent cone of 42.28 deg (A = 2.598 h^2)\n\
         \x20   //   Berkovich(tip_radius: 2e-4)                    the same with a rounded tip (mm), also Vickers, CubeCorner\n",
    );
    let punch = serde_json::to_value(&cfg.punch).unwrap_or(Value::Null);
    out.push_str(&format!("    punch: {},\n", ron_inline(&punch)));
    out.push_str(
        "    // The model. Contact: Vertical (the paper's: gap at the reference radius, vertical\n\
         \x20   // reaction), Normal (gap of the displaced node along the punch's normal, frictionless)\n\
         \x20   // or Normal(friction: 0.1) (Coulomb; docs/validation-contact.md). Kinematics: Small (the\n\
         \x20   // paper's) or Finite (logarithmic strain, needs Normal contact, with or without friction;\n\
         \x20   // docs/validation-finite-strain.md). Left out: Vertical and Small for a depth history,\n\
         \x20   // Normal and Finite for measured data.\n",
    );
    out.push_str(&format!(
        "    contact: {},\n    kinematics: {:?},\n",
        ron_contact(cfg.contact),
        cfg.kinematics
    ));

    let forms = crate::config::law_forms();
    let mut line = String::from("    // Constitutive law, one of");
    for (k, form) in forms.iter().enumerate() {
        let sep = if k + 1 == forms.len() { "." } else { "," };
        if line.len() + form.len() + 2 > 100 {
            out.push_str(&line);
            out.push('\n');
            line = String::from("    //");
        }
        line.push_str(&format!(" {form}{sep}"));
    }
    out.push_str(&line);
    out.push_str(&format!("\n    law: {}(\n", cfg.law.variant()));
    block(&mut out, "        ", &cfg.law.lines());
    out.push_str("    ),\n");

    if let Some(history) = &cfg.history {
        history_block(&mut out, history);
    }
    if let Some(d) = &cfg.data {
        out.push_str(&data_block(d));
    }

    solver_block(&mut out, &cfg.solver);
    if let Some(tests) = &cfg.tests {
        out.push_str(&ron_section(
            "tests",
            "A joint fit (docs/joint-fits.md): the tests share the law's parameters; each gives\n\
             \x20   // its `history` or `data`, and may give its own `name`, `specimen`, `punch`, `contact`\n\
             \x20   // and `weight` (default 1/(n F_max^2)).",
            tests,
        ));
    }
    if let Some(id) = &cfg.identify {
        identify_block(&mut out, cfg, id);
    }
    if let Some(design) = &cfg.design {
        out.push_str(&ron_section(
            "design",
            "Candidate protocols that `indentify design` ranks (docs/design.md).",
            design,
        ));
    }
    out.push_str(")\n");
    out
}

/// The annotated `specimen: ...(` section, without its closing line.
fn specimen_block(out: &mut String, specimen: Specimen) {
    match specimen {
        Specimen::Cylinder {
            radius,
            height,
            nr,
            nz,
            grading_r,
            grading_z,
        } => {
            out.push_str("    specimen: Cylinder(\n");
            block(
                out,
                "        ",
                &[
                    (format!("radius: {},", num(radius)), "mm, > 0".into()),
                    (format!("height: {},", num(height)), "mm, > 0".into()),
                    (
                        format!("nr: {nr},"),
                        "elements along r, an integer in [1, 2000]".into(),
                    ),
                    (
                        format!("nz: {nz},"),
                        "elements along z, an integer in [1, 2000]".into(),
                    ),
                    (
                        format!("grading_r: {},", num(grading_r)),
                        "size ratio of neighbouring elements along r, in [1, 3] (1 = uniform)"
                            .into(),
                    ),
                    (
                        format!("grading_z: {},", num(grading_z)),
                        "size ratio of neighbouring elements along z, in [1, 3] (1 = uniform)"
                            .into(),
                    ),
                ],
            );
        }
        Specimen::Auto {
            elements_in_contact,
            size_factor,
            grading,
        } => {
            out.push_str("    specimen: Auto(\n");
            block(
                out,
                "        ",
                &[
                    (
                        format!("elements_in_contact: {elements_in_contact},"),
                        "element edges across the contact-radius bound, in [2, 64]".into(),
                    ),
                    (
                        format!("size_factor: {},", num(size_factor)),
                        "specimen radius and height in contact-radius bounds, in [5, 10000]".into(),
                    ),
                    (
                        format!("grading: {},", num(grading)),
                        "largest size ratio of neighbouring elements beyond the core, in [1.05, 3]"
                            .into(),
                    ),
                ],
            );
        }
    }
}

/// The annotated `history: (...)` section.
fn history_block(out: &mut String, history: &crate::config::History) {
    out.push_str(
        "    // Punch depth history from t = 0, h = 0: each segment moves the punch linearly to\n\
         \x20   // `depth` (mm, positive into the body) over `duration` (s, > 0) in `steps` equal time\n\
         \x20   // steps (>= 1). A punch withdrawn past contact loss gives F = 0.\n\
         \x20   history: (\n        segments: [\n",
    );
    let mut previous = 0.0;
    let lines: Vec<(String, String)> = history
        .segments
        .iter()
        .map(|seg| {
            // a load-controlled segment (`force`) is written as such
            let (key, value) = match (seg.depth, seg.force) {
                (_, Some(f)) => ("force", f),
                (d, None) => ("depth", d.unwrap_or(previous)),
            };
            let what = if key == "force" {
                "load control"
            } else if value > previous {
                "load"
            } else if value < previous {
                "unload"
            } else {
                "hold"
            };
            if key == "depth" {
                previous = value;
            }
            let text = match (seg.pdot_over_p, seg.duration) {
                (Some(r), _) => format!(
                    "(force: {}, pdot_over_p: {}, steps: {}),",
                    num(value),
                    num(r),
                    seg.steps
                ),
                (None, d) => format!(
                    "(duration: {}, {key}: {}, steps: {}),",
                    num(d.unwrap_or(f64::NAN)),
                    num(value),
                    seg.steps
                ),
            };
            let what = if seg.pdot_over_p.is_some() {
                "load control at constant Pdot/P (1/s)"
            } else {
                what
            };
            (text, what.into())
        })
        .collect();
    block(out, "            ", &lines);
    out.push_str("        ],\n    ),\n");
}

/// The annotated `solver: (...)` section.
fn solver_block(out: &mut String, o: &crate::config::SolverConfig) {
    out.push_str(
        "    // Optional: numerical options of the direct solver (the defaults are shown).\n    solver: (\n",
    );
    block(
        out,
        "        ",
        &[
            (
                format!("residual_tol: {},", num(o.residual_tol)),
                "relative equilibrium residual, in (0, 1)".into(),
            ),
            (
                format!("max_iterations: {},", o.max_iterations),
                "global Newton iterations per step, in [1, 10000]".into(),
            ),
            (
                format!("max_cuts: {},", o.max_cuts),
                "halvings of a failing step before giving up, in [0, 30]".into(),
            ),
            (
                format!("active_set_check_tol: {},", num(o.active_set_check_tol)),
                "relative residual at which the active set is checked, in [0, 1)".into(),
            ),
            (
                format!("gap_tol: {},", num(o.gap_tol)),
                "relative penetration before a node is activated, in [0, 1)".into(),
            ),
            (
                format!("lambda_tol: {},", num(o.lambda_tol)),
                "relative tensile reaction before a node is released, in [0, 1)".into(),
            ),
        ],
    );
    out.push_str("    ),\n");
}

/// A section written as indented RON after a comment (`tests`, `design`: lists whose
/// entries are the other sections' fields).
fn ron_section<T: serde::Serialize>(name: &str, comment: &str, value: &T) -> String {
    let pretty = ron::ser::PrettyConfig::new()
        .struct_names(false)
        .extensions(ron::extensions::Extensions::IMPLICIT_SOME)
        .indentor("    ".to_string());
    let text = ron::ser::to_string_pretty(value, pretty).unwrap_or_else(|_| "[]".to_string());
    // `name: "..."`, not `name: Some("...")`: the loader takes implicit `Some` (its own
    // `#![enable(...)]` line is not needed inside the file)
    let text = match text.strip_prefix("#![enable(implicit_some)]") {
        Some(rest) => rest.trim_start(),
        None => &text,
    };
    format!(
        "    // {comment}\n    {name}: {},\n",
        text.replace('\n', "\n    ")
    )
}

/// The `params` lines of the `identify` section, in the law's order (names the law does
/// not have last), each with its description.
fn param_lines(cfg: &Config, id: &IdentifySection) -> Vec<(String, String)> {
    let infos = cfg.law.param_infos();
    let mut listed: Vec<&str> = cfg
        .law
        .named_params()
        .iter()
        .map(|(n, _)| *n)
        .filter(|n| id.params.contains_key(*n))
        .collect();
    // names the law does not have (rejected on load) keep their place at the end
    let extra: Vec<&str> = id
        .params
        .keys()
        .map(String::as_str)
        .filter(|n| !listed.contains(n))
        .collect();
    listed.extend(extra);
    let mut lines = Vec::new();
    for name in listed {
        let code = match id.params[name] {
            ParamSetting::Free {
                start,
                lower,
                upper,
                scaling,
            } => {
                let mut fields: Vec<String> =
                    [("start", start), ("lower", lower), ("upper", upper)]
                        .iter()
                        .filter_map(|(k, v)| v.map(|v| format!("{k}: {}", num(v))))
                        .collect();
                if let Some(sc) = scaling {
                    fields.push(format!("scaling: {sc:?}"));
                }
                format!("\"{name}\": Free({}),", fields.join(", "))
            }
            ParamSetting::Fixed { value: Some(v) } => {
                format!("\"{name}\": Fixed(value: {}),", num(v))
            }
            ParamSetting::Fixed { value: None } => format!("\"{name}\": Fixed(),"),
        };
        let note = infos
            .iter()
            .find(|i| i.name == name)
            .map_or_else(String::new, |i| format!("{} ({})", i.description, i.unit));
        lines.push((code, note));
    }
    lines
}

/// The annotated `identify: (...)` section.
fn identify_block(out: &mut String, cfg: &Config, id: &IdentifySection) {
    out.push_str(
        "    // Optional: what `indentify identify` identifies, and how. A parameter listed in `params`\n\
         \x20   // is Free (identified from `start` within [lower, upper]; the optimizer sees Log: ln c,\n\
         \x20   // Bounds: (c - lower)/(upper - lower), or Linear: c/|start|) or Fixed (held at `value`).\n\
         \x20   // An omitted start or value is the `law` value, omitted bounds the law's admissible range,\n\
         \x20   // an omitted scaling Log (Linear if the lower bound is negative); a parameter not listed\n\
         \x20   // is held at its `law` value; without this section every parameter but nu is identified\n\
         \x20   // from its `law` value. Without --data, the data are this file's curve simulated at its\n\
         \x20   // `law` values. --free, --fixed, --start, --method and --max-iter override this section.\n\
         \x20   identify: (\n        params: {\n",
    );
    let lines = param_lines(cfg, id);
    block(out, "            ", &lines);
    out.push_str("        },\n");
    let st = &id.stop;
    block(
        out,
        "        ",
        &[
            (
                format!("method: {:?},", id.method),
                "Bfgs (BFGS + Armijo backtracking, the paper's), Lbfgs (More-Thuente), \
                 Lbfgsb (bounds in the method), Lm (Levenberg-Marquardt)"
                    .into(),
            ),
            (
                format!("memory: {},", id.memory),
                "correction pairs of Lbfgs and Lbfgsb, in [1, 100]".into(),
            ),
            (
                format!("initial_step: {},", num(id.initial_step)),
                "first trial step in scaled variables (0.5: a factor e^0.5 on a Log parameter)"
                    .into(),
            ),
        ],
    );
    out.push_str("        stop: (\n");
    block(
        out,
        "            ",
        &[
            (
                format!("gradient_tol: {},", num(st.gradient_tol)),
                "|projected gradient in scaled variables| / J_ref, J_ref = 1/2 sum F_exp^2".into(),
            ),
            (
                format!("relative_decrease_tol: {},", num(st.relative_decrease_tol)),
                "relative decrease of J over one iteration, in [0, 1)".into(),
            ),
            (
                format!("target_cost: {},", num(st.target_cost)),
                "J / J_ref to stop at (0: off)".into(),
            ),
            (
                format!("max_iterations: {},", st.max_iterations),
                "iteration limit".into(),
            ),
            (
                format!(
                    "max_line_search_evaluations: {},",
                    st.max_line_search_evaluations
                ),
                "trial points of one line search before it has stalled".into(),
            ),
            (
                format!("roundoff_cost: {},", num(st.roundoff_cost)),
                "J / J_ref under which a stall counts as converged".into(),
            ),
            (
                match st.step_sigma {
                    Some(f) => format!("step_sigma: {},", num(f)),
                    None => "step_sigma: None,".into(),
                },
                "Lm: stop when the last step moves every parameter by < this x its std. dev. (None: off)".into(),
            ),
            (
                match st.lm_radius {
                    Some(r) => format!("lm_radius: {},", num(r)),
                    None => "lm_radius: None,".into(),
                },
                "Lm: the first step moves no scaled parameter by more than this (1: a factor e; None: off)".into(),
            ),
            (
                format!("proposed_step: {},", st.proposed_step),
                "Lm: also stop when the next Gauss-Newton step is < step_sigma x every std. dev. after a step the model predicted".into(),
            ),
            (
                format!("lm_stop_rejected: {},", st.lm_stop_rejected),
                "Lm: stop a trial's forward run once its cost so far rejects it (same results)".into(),
            ),
            (
                format!("lm_damping: {:?},", st.lm_damping),
                "Lm: damping update Classic, Nielsen, MarquardtFletcher, GainCapped or Delayed".into(),
            ),
        ],
    );
    out.push_str("        ),\n");
    block(
        out,
        "        ",
        &[(
            format!("identifiability: {},", id.identifiability),
            "standard deviations and correlations at the optimum (one sensitivity solve)".into(),
        )],
    );
    out.push_str("    ),\n");
}

/// `name: value,` lines of the law with the library's description, unit and range.
/// The `data` section: the record, its format and test, its preprocessing (written out in
/// full, every default included).
fn data_block(d: &DataSection) -> String {
    let pretty = ron::ser::PrettyConfig::new()
        .struct_names(false)
        .indentor("    ".to_string());
    let pre =
        ron::ser::to_string_pretty(&d.preprocessing, pretty).unwrap_or_else(|_| "()".to_string());
    let pre = pre.replace('\n', "\n        ");
    let mut out = String::from(
        "    // Measured record: its preprocessed depth drives the simulation and its force is the\n\
         \x20   // data to fit. `file` is relative to this file's folder; `format` one of Auto, Csv,\n\
         \x20   // AntonPaar, AntonPaarMulti, HysitronTxt, Hld; `test` (from 1) picks one test of a\n\
         \x20   // multi-test file. Preprocessing runs drift, zero_point, compliance, segments, resample\n\
         \x20   // in that order (None skips a step; see docs/tutorial-real-data.md).\n\
         \x20   data: (\n",
    );
    out.push_str(&format!("        file: {:?},\n", d.file));
    out.push_str(&format!("        format: {:?},\n", d.format));
    if let Some(t) = d.test {
        out.push_str(&format!("        test: {t},\n"));
    }
    out.push_str(&format!("        preprocessing: {pre},\n"));
    out.push_str(&format!(
        "        // equal sub-steps of the forward solve between consecutive points (the force\n\
         \x20       // compared with the data at the points only), in [1, {}]\n\
         \x20       substeps: {},\n    ),\n",
        crate::config::MAX_DATA_SUBSTEPS,
        d.substeps
    ));
    out
}

/// Appends `indent + code  // comment` lines with the comments aligned.
fn block(out: &mut String, indent: &str, lines: &[(String, String)]) {
    let width = lines.iter().map(|(c, _)| c.len()).max().unwrap_or(0);
    for (code, comment) in lines {
        out.push_str(&format!("{indent}{code:<width$} // {comment}\n"));
    }
}

/// A float as RON text that parses back to the same bits (`20000.0`, `1e-10`).
fn num(v: f64) -> String {
    format!("{v:?}")
}

/// One-line RON of a serialized value: `Cone(half_angle_deg: 68.0)`, `[0.0, 1.0]`.
/// The contact kind as a configuration writes it.
fn ron_contact(c: indentify_contact::ContactKind) -> String {
    use indentify_contact::ContactKind;
    match c {
        ContactKind::Vertical => "Vertical".into(),
        ContactKind::Normal => "Normal".into(),
        ContactKind::NormalFriction { friction } => format!("Normal(friction: {})", num(friction)),
    }
}

fn ron_inline(v: &Value) -> String {
    let fields = |map: &serde_json::Map<String, Value>| {
        map.iter()
            .map(|(k, v)| format!("{k}: {}", ron_inline(v)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    match v {
        Value::Object(map) => match map.iter().next() {
            Some((variant, Value::Object(inner)))
                if map.len() == 1 && variant.starts_with(|c: char| c.is_ascii_uppercase()) =>
            {
                format!("{variant}({})", fields(inner))
            }
            _ => format!("({})", fields(map)),
        },
        Value::Array(a) => format!(
            "[{}]",
            a.iter().map(ron_inline).collect::<Vec<_>>().join(", ")
        ),
        Value::Number(n) => match n.as_f64() {
            Some(f) if n.is_f64() => num(f),
            _ => n.to_string(),
        },
        other => other.to_string(),
    }
}

/// How a configuration saved as `config` names the data file `file` (both as given, from
/// the working directory): relative to the configuration's folder, where `data.file` is
/// looked up ([`crate::config::DataSection::path`]), or absolute when the two share no
/// root.
///
/// # Errors
/// A file or folder that does not exist.
pub fn data_path_for(file: &Path, config: &Path) -> std::io::Result<String> {
    let file = std::fs::canonicalize(file)?;
    let dir = config
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let dir = std::fs::canonicalize(dir)?;
    let f: Vec<_> = file.components().collect();
    let d: Vec<_> = dir.components().collect();
    let common = f.iter().zip(&d).take_while(|(a, b)| a == b).count();
    if common == 0 {
        return Ok(file.display().to_string());
    }
    let mut relative = PathBuf::new();
    for _ in common..d.len() {
        relative.push("..");
    }
    for c in &f[common..] {
        relative.push(c);
    }
    Ok(relative.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::parse;
    use indentify_contact::Punch;

    /// `init --data FILE --out CONFIG` names the record relative to the configuration's
    /// folder, where `data.file` is looked up: found again from there.
    #[test]
    fn data_paths_are_relative_to_the_configuration() {
        let tmp = tempfile::tempdir().unwrap();
        let root = tmp.path();
        std::fs::create_dir_all(root.join("a/data")).unwrap();
        std::fs::create_dir_all(root.join("b/c")).unwrap();
        let file = root.join("a/data/x.txt");
        std::fs::write(&file, "t,F\n").unwrap();
        let config = root.join("b/c/cfg.ron");
        let written = data_path_for(&file, &config).unwrap();
        assert_eq!(
            written,
            format!("..{0}..{0}a{0}data{0}x.txt", std::path::MAIN_SEPARATOR)
        );
        let found = std::fs::canonicalize(root.join("b/c").join(&written)).unwrap();
        assert_eq!(found, std::fs::canonicalize(&file).unwrap());
        assert_eq!(
            data_path_for(&file, &root.join("a/data/cfg.ron")).unwrap(),
            "x.txt"
        );
        assert!(data_path_for(&root.join("missing.txt"), &config).is_err());
    }

    /// `check` prints a joint configuration resolved: its `tests` (and a `design`
    /// section) are written out and parse back to the same configuration.
    #[test]
    fn annotated_keeps_tests_and_design() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
        for file in ["r2-multi-rate.ron", "r2-design.ron"] {
            let text = std::fs::read_to_string(dir.join(file)).unwrap();
            let cfg = parse(&text, file).unwrap();
            let written = annotated(&cfg, &["a header".to_string()]);
            let back = parse(&written, file).unwrap();
            assert!(back.tests.is_some() || back.design.is_some(), "{file}");
            assert!(
                !written.contains("Some(") && !written.contains("#!["),
                "{written}"
            );
            assert_eq!(
                (back.tests, back.design),
                (cfg.tests, cfg.design),
                "{written}"
            );
        }
        let mut cfg = Reference::R1Maxwell.config();
        let test = crate::config::TestSpec {
            name: Some("a \"quoted\" name".into()),
            specimen: None,
            punch: Some(Punch::Sphere { radius: 0.5 }),
            contact: Some(indentify_contact::ContactKind::Normal),
            history: cfg.history.clone(),
            data: None,
            weight: Some(2.0),
        };
        cfg.tests = Some(vec![test]);
        cfg.history = None;
        let written = annotated(&cfg, &[]);
        assert_eq!(parse(&written, "t").unwrap(), cfg, "{written}");
    }

    #[test]
    fn every_template_parses_back_exactly() {
        for r in Reference::ALL {
            let text = template(r);
            let cfg = parse(&text, "template").unwrap();
            assert_eq!(cfg, r.config(), "{text}");
            cfg.validate().unwrap();
        }
    }

    #[test]
    fn annotated_round_trips_every_punch_and_odd_numbers() {
        let punches = [
            Punch::Sphere { radius: 0.25 },
            Punch::Flat { radius: 1e-3 },
            Punch::SpheroCone {
                radius: 0.1,
                half_angle_deg: 70.3,
            },
            Punch::Tabulated {
                r: vec![0.0, 0.1, 1.0],
                z: vec![0.0, 0.01, 0.7],
            },
        ];
        for punch in punches {
            let mut cfg = Reference::R2NortonHoff.config();
            cfg.punch = punch;
            cfg.solver.residual_tol = 1.234_567_890_123e-11;
            if let Specimen::Cylinder { radius, .. } = &mut cfg.specimen {
                *radius = 1.0 / 3.0;
            }
            let text = annotated(&cfg, &[]);
            assert_eq!(parse(&text, "t").unwrap(), cfg, "{text}");
        }
    }

    #[test]
    fn shipped_examples_are_the_init_output() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
        for (kind, r) in [
            ("elastic", Reference::R0Elastic),
            ("maxwell", Reference::R1Maxwell),
            ("norton-hoff", Reference::R2NortonHoff),
        ] {
            let shipped = std::fs::read_to_string(dir.join(r.example_file())).unwrap();
            assert!(
                shipped == template(r),
                "examples/{} is stale: regenerate it with \
                 `cargo run -p indentify-cli -- init {kind} > examples/{}`",
                r.example_file(),
                r.example_file()
            );
        }
    }

    #[test]
    fn template_comments_carry_library_ranges() {
        let t = template(Reference::R2NortonHoff);
        assert!(t.contains("sY: 500.0,"), "{t}");
        assert!(t.contains("nu: 0.3,") && t.contains("(-1, 0.5)"), "{t}");
    }
}
