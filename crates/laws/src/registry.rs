//! The registry of materials: configuration name → constructor and parameter metadata,
//! so that adding a law is one file (the law and its [`LawEntry`]) and one line
//! ([`REGISTRY`]). A specification is given as [`SpecValue`]s, independent of any file
//! format (the application layer converts its configuration into them).

use crate::LawError;
use crate::law::{Law, ParamInfo};
use crate::material::{LawMaterial, Material};
use crate::{Elastic, Maxwell, NortonHoff};

/// A value of a law's specification.
#[derive(Clone, Debug, PartialEq)]
pub enum SpecValue {
    /// A number.
    Number(f64),
    /// A named variant with named fields (`Linear(H: 2000.0)`, `Norton(K: 200.0, m: 3.0)`,
    /// `Power(n: 0.2)`); an anonymous struct (`(g: 0.3, tau: 1.0)`) has an empty name and
    /// a unit variant (`None`) no fields.
    Variant {
        /// The variant's name (empty for an anonymous struct).
        name: String,
        /// Its named fields, in the order written.
        fields: Vec<(String, SpecValue)>,
    },
    /// A list `[a, b, ...]`.
    List(Vec<SpecValue>),
    /// A tuple `(a, b)`.
    Tuple(Vec<SpecValue>),
}

/// A material built from its specification, with the parameter values in its order.
#[derive(Debug)]
pub struct Built {
    /// The material (structure: hardening form, number of terms, tables).
    pub material: Box<dyn Material>,
    /// Parameter values in the order of `material.params()`, range-checked.
    pub params: Vec<f64>,
}

/// The named fields of a law's configuration variant, in the order written.
pub type SpecFields = [(String, SpecValue)];

/// A registered constructor.
pub type Constructor = fn(&SpecFields) -> Result<Built, LawError>;

/// The shape of one field of a law's configuration variant, so that a configuration
/// reader can parse it (nested variant names included) without knowing the law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FieldKind {
    /// A number.
    Number,
    /// One of these named variants (`hardening: Voce(Q: .., b: ..)`).
    OneOf(&'static [VariantSchema]),
    /// A list of anonymous structs with these fields (`terms: [(g: .., tau: ..), ...]`).
    ListOf(&'static [FieldSchema]),
    /// A list of number pairs (`points: [(eps_p, sigma), ...]`).
    Pairs,
}

/// One field of a variant: name, shape, and whether it may be omitted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldSchema {
    /// Field name as written in configurations.
    pub name: &'static str,
    /// Its shape.
    pub kind: FieldKind,
    /// `true` when the field may be omitted (`rate` of `Plastic`).
    pub optional: bool,
}

/// A named variant and its fields (`Voce` with `Q`, `b`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VariantSchema {
    /// Variant name.
    pub name: &'static str,
    /// Its fields.
    pub fields: &'static [FieldSchema],
}

/// A required number field (for schemas).
pub const fn number(name: &'static str) -> FieldSchema {
    FieldSchema {
        name,
        kind: FieldKind::Number,
        optional: false,
    }
}

/// One registered law.
#[derive(Clone, Copy, Debug)]
pub struct LawEntry {
    /// Name in reports and `law_by_name` (`plastic`).
    pub name: &'static str,
    /// Configuration variant (`Plastic`).
    pub variant: &'static str,
    /// One line for `--help` and `init`.
    pub summary: &'static str,
    /// A complete configuration example of the variant.
    pub example: &'static str,
    /// The fields of the variant and their shapes (what a configuration reader parses).
    pub fields: &'static [FieldSchema],
    /// The constructor from the variant's named fields.
    pub build: Constructor,
}

/// Every registered law, simplest first. Adding a law: one line here.
pub const REGISTRY: &[LawEntry] = &[
    ELASTIC,
    MAXWELL,
    NORTON_HOFF,
    crate::plastic::ENTRY,
    crate::prony::ENTRY,
    #[cfg(feature = "example-law")]
    crate::example_material::ENTRY,
];

/// The configuration variants of [`REGISTRY`], in its order (for a reader's
/// `deserialize_enum`; checked against the registry by a test).
pub const VARIANTS: &[&str] = &[
    "Elastic",
    "Maxwell",
    "NortonHoff",
    "Plastic",
    "Prony",
    #[cfg(feature = "example-law")]
    "Burgers",
];

/// The entry whose name (`plastic`) or variant (`Plastic`) is `key`.
pub fn entry(key: &str) -> Option<&'static LawEntry> {
    REGISTRY.iter().find(|e| e.name == key || e.variant == key)
}

/// Builds the law `variant` (name or variant) from its fields.
///
/// # Errors
/// [`LawError::Spec`] naming an unknown law, a missing or unknown field, a value of the
/// wrong kind; [`LawError::Parameter`] for a value outside its range.
pub fn build(variant: &str, fields: &[(String, SpecValue)]) -> Result<Built, LawError> {
    let e = entry(variant).ok_or_else(|| LawError::Spec {
        law: "law",
        field: "law".into(),
        message: format!(
            "unknown law `{variant}`; registered: {}",
            REGISTRY
                .iter()
                .map(|e| e.variant)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    })?;
    (e.build)(fields)
}

/// Reads the fields of one variant: numbers and sub-variants by name, each consumed at
/// most once, with [`Fields::finish`] refusing any field left over.
pub struct Fields<'a> {
    law: &'static str,
    prefix: String,
    fields: &'a [(String, SpecValue)],
    used: Vec<bool>,
}

impl<'a> Fields<'a> {
    /// The fields of `law` at path `prefix` (`""` for the law's own, `"hardening."` ...).
    pub fn new(law: &'static str, prefix: &str, fields: &'a [(String, SpecValue)]) -> Self {
        Fields {
            law,
            prefix: prefix.into(),
            fields,
            used: vec![false; fields.len()],
        }
    }
    /// An error about `field`.
    pub fn error(&self, field: &str, message: String) -> LawError {
        LawError::Spec {
            law: self.law,
            field: format!("{}{field}", self.prefix),
            message,
        }
    }
    /// The value of `field`, if given.
    pub fn get(&mut self, field: &str) -> Option<&'a SpecValue> {
        let i = self.fields.iter().position(|(n, _)| n == field)?;
        self.used[i] = true;
        Some(&self.fields[i].1)
    }
    /// The number `field`.
    ///
    /// # Errors
    /// Missing or not a number.
    pub fn number(&mut self, field: &str) -> Result<f64, LawError> {
        match self.get(field) {
            Some(SpecValue::Number(v)) => Ok(*v),
            Some(other) => Err(self.error(field, format!("expected a number, got {other:?}"))),
            None => Err(self.error(field, "missing (a number)".into())),
        }
    }
    /// Refuses fields that were not read.
    ///
    /// # Errors
    /// The first unknown field, with the accepted ones.
    pub fn finish(self, accepted: &[&str]) -> Result<(), LawError> {
        match self.used.iter().position(|u| !u) {
            None => Ok(()),
            Some(i) => Err(self.error(
                &self.fields[i].0,
                format!("unknown field; accepted: {}", accepted.join(", ")),
            )),
        }
    }
}

/// Parameter values in the order of `infos`, from `(name, value)` pairs, range-checked.
///
/// # Errors
/// [`LawError::Parameter`] for a value outside its range.
pub fn ordered_params(mat: &dyn Material, values: &[(&str, f64)]) -> Result<Vec<f64>, LawError> {
    let params: Vec<f64> = mat
        .params()
        .iter()
        .map(|p: &ParamInfo| {
            values
                .iter()
                .find(|(n, _)| *n == p.name)
                .map(|v| v.1)
                .unwrap_or(f64::NAN)
        })
        .collect();
    mat.check_params(&params)?;
    Ok(params)
}

/// A stress-only law: one number field per parameter, nothing else.
fn build_law(law: &'static dyn Law, fields: &[(String, SpecValue)]) -> Result<Built, LawError> {
    let mut f = Fields::new(law.name(), "", fields);
    let names: Vec<&str> = law.params().iter().map(|p| p.name).collect();
    let mut values = Vec::new();
    for &n in &names {
        values.push((n, f.number(n)?));
    }
    f.finish(&names)?;
    let material = LawMaterial(law);
    let params = ordered_params(&material, &values)?;
    Ok(Built {
        material: Box::new(material),
        params,
    })
}

const ELASTIC: LawEntry = LawEntry {
    name: "elastic",
    variant: "Elastic",
    summary: "linear isotropic elasticity",
    example: "Elastic(E: 200000.0, nu: 0.3)",
    fields: &[number("E"), number("nu")],
    build: |f| build_law(&Elastic, f),
};
const MAXWELL: LawEntry = LawEntry {
    name: "maxwell",
    variant: "Maxwell",
    summary: "Maxwell viscoelasticity (deviatoric dashpot)",
    example: "Maxwell(E: 3000.0, nu: 0.35, eta: 20000.0)",
    fields: &[number("E"), number("nu"), number("eta")],
    build: |f| build_law(&Maxwell, f),
};
const NORTON_HOFF: LawEntry = LawEntry {
    name: "norton-hoff",
    variant: "NortonHoff",
    summary: "Norton-Hoff elastoviscoplasticity with a yield stress",
    example: "NortonHoff(E: 100000.0, nu: 0.3, K: 1500.0, m: 5.0, sY: 500.0)",
    fields: &[
        number("E"),
        number("nu"),
        number("K"),
        number("m"),
        number("sY"),
    ],
    build: |f| build_law(&NortonHoff, f),
};

#[cfg(test)]
mod tests {
    use super::*;

    fn num(n: &str, v: f64) -> (String, SpecValue) {
        (n.into(), SpecValue::Number(v))
    }
    fn var(n: &str, name: &str, fields: Vec<(String, SpecValue)>) -> (String, SpecValue) {
        (
            n.into(),
            SpecValue::Variant {
                name: name.into(),
                fields,
            },
        )
    }

    /// The system shall build every registered law from its fields, with parameters in
    /// the law's order, and find entries by name and variant.
    #[test]
    fn every_entry_builds_and_is_found() {
        let variants: Vec<&str> = REGISTRY.iter().map(|e| e.variant).collect();
        assert_eq!(variants, VARIANTS);
        for e in REGISTRY {
            assert_eq!(entry(e.name).unwrap().variant, e.variant);
            assert_eq!(entry(e.variant).unwrap().name, e.name);
        }
        let b = build(
            "NortonHoff",
            &[
                num("E", 1e5),
                num("nu", 0.3),
                num("K", 1500.0),
                num("m", 5.0),
                num("sY", 500.0),
            ],
        )
        .unwrap();
        assert_eq!(b.params, [1e5, 0.3, 1500.0, 5.0, 500.0]);
        assert_eq!(b.material.name(), "norton-hoff");
        let b = build(
            "Plastic",
            &[
                num("E", 7e4),
                num("nu", 0.3),
                num("sY", 300.0),
                var("hardening", "Voce", vec![num("Q", 150.0), num("b", 40.0)]),
                var("rate", "Norton", vec![num("K", 200.0), num("m", 3.0)]),
            ],
        )
        .unwrap();
        assert_eq!(b.params, [7e4, 0.3, 300.0, 150.0, 40.0, 200.0, 3.0]);
        let names: Vec<&str> = b.material.params().iter().map(|p| p.name).collect();
        assert_eq!(names, ["E", "nu", "sY", "Q", "b", "K", "m"]);
        let term = |g: f64, tau: f64| SpecValue::Variant {
            name: String::new(),
            fields: vec![num("g", g), num("tau", tau)],
        };
        let b = build(
            "prony",
            &[
                num("E", 3000.0),
                num("nu", 0.35),
                (
                    "terms".into(),
                    SpecValue::List(vec![term(0.3, 0.1), term(0.2, 2.0)]),
                ),
            ],
        )
        .unwrap();
        assert_eq!(b.params, [3000.0, 0.35, 0.3, 0.1, 0.2, 2.0]);
        assert_eq!(b.material.n_internal(), 8);
    }

    /// A valid value for a parameter name (the schema test's numbers).
    fn sample(name: &str) -> f64 {
        match name {
            "E" | "Gk" => 1000.0,
            "nu" => 0.3,
            "m" => 2.0,
            "g" => 0.2,
            _ => 0.5,
        }
    }

    fn sample_fields(fields: &[FieldSchema], pick: usize) -> Vec<(String, SpecValue)> {
        fields
            .iter()
            .map(|f| {
                let v = match f.kind {
                    FieldKind::Number => SpecValue::Number(sample(f.name)),
                    FieldKind::OneOf(vs) => {
                        let v = &vs[pick % vs.len()];
                        SpecValue::Variant {
                            name: v.name.into(),
                            fields: sample_fields(v.fields, pick),
                        }
                    }
                    FieldKind::ListOf(inner) => SpecValue::List(vec![
                        SpecValue::Variant {
                            name: String::new(),
                            fields: sample_fields(inner, pick),
                        };
                        2
                    ]),
                    FieldKind::Pairs => SpecValue::List(
                        [(0.0, 1.0), (1.0, 2.0)]
                            .iter()
                            .map(|&(a, b)| {
                                SpecValue::Tuple(vec![SpecValue::Number(a), SpecValue::Number(b)])
                            })
                            .collect(),
                    ),
                };
                (f.name.to_string(), v)
            })
            .collect()
    }

    /// The system shall describe every law's fields by a schema that its constructor
    /// accepts: a specification generated from the schema (every variant of every
    /// `OneOf`, optional fields given and omitted) builds.
    #[test]
    fn schemas_agree_with_the_constructors() {
        for e in REGISTRY {
            for pick in 0..5 {
                let all = sample_fields(e.fields, pick);
                (e.build)(&all).unwrap_or_else(|err| panic!("{} pick {pick}: {err}", e.name));
                let required: Vec<(String, SpecValue)> = all
                    .iter()
                    .zip(e.fields)
                    .filter(|(_, f)| !f.optional)
                    .map(|(v, _)| v.clone())
                    .collect();
                (e.build)(&required).unwrap_or_else(|err| panic!("{} required: {err}", e.name));
            }
        }
    }

    /// The system shall name what is wrong: an unknown law, hardening or rate kind, an
    /// unknown or missing field, a bad table point, a value outside its range.
    #[test]
    fn bad_specifications_name_the_field() {
        let base = || vec![num("E", 7e4), num("nu", 0.3), num("sY", 300.0)];
        let with = |extra: Vec<(String, SpecValue)>| {
            let mut f = base();
            f.extend(extra);
            build("Plastic", &f).unwrap_err().to_string()
        };
        let t = build("Hooke", &[]).unwrap_err().to_string();
        assert!(t.contains("Hooke") && t.contains("Plastic, Prony"), "{t}");
        let t = with(vec![var("hardening", "Ludwik", vec![])]);
        assert!(
            t.contains("hardening")
                && t.contains("Ludwik")
                && t.contains("Linear, Power, Voce, Swift, Table"),
            "{t}"
        );
        let t = with(vec![
            var("hardening", "Linear", vec![num("H", 1.0)]),
            var("rate", "Perzyna", vec![]),
        ]);
        assert!(
            t.contains("rate") && t.contains("Perzyna") && t.contains("Norton"),
            "{t}"
        );
        let t = with(vec![var("hardening", "Linear", vec![num("H", -1.0)])]);
        assert!(t.contains("`H`") && t.contains("[0, inf)"), "{t}");
        let t = with(vec![var(
            "hardening",
            "Linear",
            vec![num("H", 1.0), num("Q", 2.0)],
        )]);
        assert!(
            t.contains("hardening.Q") && t.contains("unknown field"),
            "{t}"
        );
        let t = with(vec![var("hardening", "Voce", vec![num("Q", 1.0)])]);
        assert!(t.contains("hardening.b") && t.contains("missing"), "{t}");
        let t = with(vec![]);
        assert!(t.contains("hardening") && t.contains("missing"), "{t}");
        let pts = SpecValue::List(vec![
            SpecValue::Tuple(vec![SpecValue::Number(0.0), SpecValue::Number(300.0)]),
            SpecValue::Tuple(vec![SpecValue::Number(0.01), SpecValue::Number(250.0)]),
        ]);
        let t = with(vec![var(
            "hardening",
            "Table",
            vec![("points".into(), pts)],
        )]);
        assert!(
            t.contains("hardening.points[1]") && t.contains("non-decreasing"),
            "{t}"
        );
        let t = build("Elastic", &[num("E", 1.0)]).unwrap_err().to_string();
        assert!(t.contains("nu") && t.contains("missing"), "{t}");
        let t = build(
            "Prony",
            &[
                num("E", 1.0),
                num("nu", 0.3),
                ("terms".into(), SpecValue::List(vec![])),
            ],
        )
        .unwrap_err()
        .to_string();
        assert!(t.contains("terms") && t.contains("1 to 8"), "{t}");
    }
}
