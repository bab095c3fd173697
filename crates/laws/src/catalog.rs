//! The catalog of registered laws, generated from [`crate::registry::REGISTRY`] alone (no
//! hand-written list): for every law its forms (one per combination of its kinds, e.g.
//! `Plastic` with each hardening form, rate-independent or `Norton`; `Prony` with two
//! terms), each form's parameters with units, ranges and descriptions as the material
//! itself declares them, and a specification of the form that the registry builds.
//!
//! A form's parameters are those of the material the registry's constructor builds from a
//! specification of that form. The specification's numbers are admissible values found by
//! trying a short list of candidates per number field (the constructor names the field it
//! refuses); they are placeholders for building, not recommended values.

use crate::LawError;
use crate::law::ParamInfo;
use crate::registry::{FieldKind, FieldSchema, LawEntry, REGISTRY, SpecValue, VariantSchema};

/// One kind choice of a law (`hardening` with its variants `Linear`, `Power`, ...).
#[derive(Clone, Debug, PartialEq)]
pub struct KindChoice {
    /// The field (`hardening`, `rate`).
    pub field: &'static str,
    /// Whether the field may be omitted (`rate`: rate-independent).
    pub optional: bool,
    /// The variants and their own fields (`Voce`: `Q`, `b`).
    pub variants: Vec<(&'static str, Vec<&'static str>)>,
}

/// One form of a law: a choice of every kind, with the parameters it has.
#[derive(Clone, Debug)]
pub struct Form {
    /// The choices, as written in a configuration (`hardening: Power, rate: Norton`;
    /// empty for a law without kinds).
    pub label: String,
    /// A specification of the form that the registry builds (placeholder numbers).
    pub spec: Vec<(String, SpecValue)>,
    /// The parameters, in the material's order, as the material declares them.
    pub params: Vec<ParamInfo>,
}

/// A registered law and its forms.
#[derive(Clone, Debug)]
pub struct LawListing {
    /// The registry entry.
    pub entry: &'static LawEntry,
    /// The kind fields (`hardening`, `rate`) and their variants.
    pub kinds: Vec<KindChoice>,
    /// The list fields (`terms` of `Prony`): field name and the fields of one element;
    /// their parameters are numbered per element (`g1`, `tau1`, `g2`, ...).
    pub lists: Vec<(&'static str, Vec<&'static str>)>,
    /// Every form (a list field is given two elements).
    pub forms: Vec<Form>,
}

impl LawListing {
    /// Every parameter of every form, once, in order of first appearance.
    pub fn params(&self) -> Vec<ParamInfo> {
        let mut out: Vec<ParamInfo> = Vec::new();
        for f in &self.forms {
            for p in &f.params {
                if !out.iter().any(|q| q.name == p.name) {
                    out.push(*p);
                }
            }
        }
        out
    }

    /// The labels of the forms that have the parameter `name`.
    pub fn forms_with(&self, name: &str) -> Vec<&str> {
        self.forms
            .iter()
            .filter(|f| f.params.iter().any(|p| p.name == name))
            .map(|f| f.label.as_str())
            .collect()
    }
}

/// Candidate values tried for a number field, in order.
const CANDIDATES: [f64; 8] = [1000.0, 0.3, 0.2, 2.0, 0.05, 10.0, 100.0, 1e4];

/// Elements given to a list field (`terms`).
const LIST_ELEMENTS: usize = 2;

/// One choice per kind field: `None` omits an optional field.
type Pick<'a> = Vec<Option<&'a VariantSchema>>;

/// Every combination of the kind fields' variants (an optional field also omitted).
fn picks(fields: &'static [FieldSchema]) -> Vec<Pick<'static>> {
    let mut out: Vec<Pick<'static>> = vec![Vec::new()];
    for f in fields {
        if let FieldKind::OneOf(vs) = f.kind {
            let mut options: Vec<Option<&VariantSchema>> = vs.iter().map(Some).collect();
            if f.optional {
                options.insert(0, None);
            }
            out = out
                .into_iter()
                .flat_map(|p| {
                    options.iter().map(move |o| {
                        let mut q = p.clone();
                        q.push(*o);
                        q
                    })
                })
                .collect();
        }
    }
    out
}

/// The numbers of a specification, by (field name, candidate index): all fields with the
/// same name share a value (the `g` of every Prony term).
struct Values(Vec<(&'static str, usize)>);

impl Values {
    fn get(&mut self, name: &'static str) -> f64 {
        if let Some(v) = self.0.iter().find(|v| v.0 == name) {
            return CANDIDATES[v.1];
        }
        self.0.push((name, 0));
        CANDIDATES[0]
    }
    /// Moves `name` (or the field it is numbered from, `g2` -> `g`) to its next candidate;
    /// `false` when there is none.
    fn bump(&mut self, name: &str) -> bool {
        let stem = name.trim_end_matches(|c: char| c.is_ascii_digit());
        let last = name.rsplit('.').next().unwrap_or(name);
        let Some(v) = self
            .0
            .iter_mut()
            .find(|v| v.0 == name || v.0 == stem || v.0 == last)
        else {
            return false;
        };
        v.1 += 1;
        v.1 < CANDIDATES.len()
    }
}

fn spec_fields(
    fields: &'static [FieldSchema],
    pick: &[Option<&'static VariantSchema>],
    values: &mut Values,
) -> Vec<(String, SpecValue)> {
    let mut k = 0;
    let mut out = Vec::new();
    for f in fields {
        let v = match f.kind {
            FieldKind::Number => Some(SpecValue::Number(values.get(f.name))),
            FieldKind::OneOf(_) => {
                let chosen = pick[k];
                k += 1;
                chosen.map(|v| SpecValue::Variant {
                    name: v.name.into(),
                    fields: spec_fields(v.fields, &[], values),
                })
            }
            FieldKind::ListOf(inner) => Some(SpecValue::List(
                (0..LIST_ELEMENTS)
                    .map(|_| SpecValue::Variant {
                        name: String::new(),
                        fields: spec_fields(inner, &[], values),
                    })
                    .collect(),
            )),
            FieldKind::Pairs => Some(SpecValue::List(
                [(0.0, 1000.0), (0.1, 1100.0)]
                    .iter()
                    .map(|&(a, b)| {
                        SpecValue::Tuple(vec![SpecValue::Number(a), SpecValue::Number(b)])
                    })
                    .collect(),
            )),
        };
        if let Some(v) = v {
            out.push((f.name.to_string(), v));
        }
    }
    out
}

/// A specification of the form `pick` of `entry` that builds, and its parameters.
fn form(
    entry: &'static LawEntry,
    pick: &[Option<&'static VariantSchema>],
) -> Result<Form, LawError> {
    let mut values = Values(Vec::new());
    let mut kinds = entry
        .fields
        .iter()
        .filter(|f| matches!(f.kind, FieldKind::OneOf(_)));
    let label = pick
        .iter()
        .map(|p| {
            let f = kinds.next().map_or("", |f| f.name);
            match p {
                Some(v) => format!("{f}: {}", v.name),
                None => format!("{f}: omitted"),
            }
        })
        .collect::<Vec<_>>()
        .join(", ");
    for _ in 0..64 {
        let spec = spec_fields(entry.fields, pick, &mut values);
        match (entry.build)(&spec) {
            Ok(b) => {
                return Ok(Form {
                    label,
                    spec,
                    params: b.material.params().to_vec(),
                });
            }
            Err(LawError::Parameter { name, .. }) if values.bump(name) => {}
            Err(LawError::Spec { ref field, .. }) if values.bump(field) => {}
            Err(e) => return Err(e),
        }
    }
    Err(LawError::Spec {
        law: entry.name,
        field: label,
        message: "no admissible placeholder values found for the catalog".into(),
    })
}

/// The listing of one registered law.
///
/// # Errors
/// A form no placeholder numbers build (a law whose ranges exclude every candidate).
pub fn listing(entry: &'static LawEntry) -> Result<LawListing, LawError> {
    let kinds = entry
        .fields
        .iter()
        .filter_map(|f| match f.kind {
            FieldKind::OneOf(vs) => Some(KindChoice {
                field: f.name,
                optional: f.optional,
                variants: vs
                    .iter()
                    .map(|v| (v.name, v.fields.iter().map(|x| x.name).collect()))
                    .collect(),
            }),
            _ => None,
        })
        .collect();
    let lists = entry
        .fields
        .iter()
        .filter_map(|f| match f.kind {
            FieldKind::ListOf(inner) => Some((f.name, inner.iter().map(|x| x.name).collect())),
            _ => None,
        })
        .collect();
    let forms = picks(entry.fields)
        .iter()
        .map(|p| form(entry, p))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(LawListing {
        entry,
        kinds,
        lists,
        forms,
    })
}

/// The listing of every registered law, in the registry's order.
///
/// # Errors
/// As [`listing`].
pub fn catalog() -> Result<Vec<LawListing>, LawError> {
    REGISTRY.iter().map(listing).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The system shall list every registered law with every combination of its kinds,
    /// each form built by the registry with the parameters the issue names.
    #[test]
    fn the_catalog_lists_every_form_of_every_law() {
        let c = catalog().unwrap();
        assert_eq!(c.len(), REGISTRY.len());
        let plastic = c.iter().find(|l| l.entry.variant == "Plastic").unwrap();
        // 5 hardening forms x (rate-independent, Norton)
        assert_eq!(plastic.forms.len(), 10);
        let names: Vec<&str> = plastic.params().iter().map(|p| p.name).collect();
        assert_eq!(
            names,
            ["E", "nu", "sY", "H", "K", "m", "n", "Q", "b", "eps0"]
        );
        assert_eq!(
            plastic.forms_with("Q"),
            [
                "hardening: Voce, rate: omitted",
                "hardening: Voce, rate: Norton"
            ]
        );
        let prony = c.iter().find(|l| l.entry.variant == "Prony").unwrap();
        let names: Vec<&str> = prony.params().iter().map(|p| p.name).collect();
        assert_eq!(names, ["E", "nu", "g1", "tau1", "g2", "tau2"]);
        assert_eq!(prony.lists, [("terms", vec!["g", "tau"])]);
        let nh = c.iter().find(|l| l.entry.variant == "NortonHoff").unwrap();
        assert_eq!(nh.forms.len(), 1);
        assert_eq!(nh.forms[0].label, "");
        for l in &c {
            for f in &l.forms {
                let b = (l.entry.build)(&f.spec).unwrap();
                let built: Vec<&str> = b.material.params().iter().map(|p| p.name).collect();
                let listed: Vec<&str> = f.params.iter().map(|p| p.name).collect();
                assert_eq!(built, listed, "{} {}", l.entry.name, f.label);
            }
        }
    }
}
