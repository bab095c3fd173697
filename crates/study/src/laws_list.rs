//! `indentify laws` and Python's `indentify.laws()`: every registered law with its
//! parameters (the names `--set law.NAME` and `identify.params.NAME` take), units,
//! admissible ranges and kinds (hardening forms, rate forms, lists of terms), generated
//! from the laws registry through `indentify_laws::catalog` (no hand-written list: a law
//! added to the registry is listed with no edit here).

use indentify_laws::catalog::{self, LawListing};
use indentify_laws::registry::SpecValue;
use serde::Serialize;

use crate::config::LawSpec;
use crate::error::{Error, ErrorKind, Result};

/// One registered law.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LawInfo {
    /// Name in reports (`plastic`).
    pub name: String,
    /// Configuration variant (`Plastic`).
    pub variant: String,
    /// One line.
    pub summary: String,
    /// A complete configuration example.
    pub example: String,
    /// The kind fields (`hardening`, `rate`) and their variants.
    pub kinds: Vec<KindInfo>,
    /// The list fields (`terms`) and the fields of one element.
    pub lists: Vec<ListInfo>,
    /// Every parameter of every form, once, in order of first appearance.
    pub parameters: Vec<ParamEntry>,
    /// Every form (a choice of every kind) and its parameters.
    pub forms: Vec<FormInfo>,
}

/// A kind field and its variants.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct KindInfo {
    /// The field (`hardening`).
    pub field: String,
    /// Whether it may be omitted (`rate`: rate-independent).
    pub optional: bool,
    /// The variants.
    pub variants: Vec<VariantInfo>,
}

/// A variant of a kind field.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VariantInfo {
    /// Its name (`Voce`).
    pub name: String,
    /// Its fields (`Q`, `b`).
    pub fields: Vec<String>,
}

/// A list field (`terms` of `Prony`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ListInfo {
    /// The field.
    pub field: String,
    /// The fields of one element (`g`, `tau`); as parameters they are numbered from 1 per
    /// element (`g1`, `tau1`, `g2`, ...).
    pub fields: Vec<String>,
}

/// One parameter.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParamEntry {
    /// The name `identify.params` and `free`/`fixed` take (`n`, `g2`).
    pub name: String,
    /// The `--set` path (`law.n`).
    pub set: String,
    /// Unit (MPa, s, -).
    pub unit: String,
    /// Meaning.
    pub description: String,
    /// Admissible range in interval notation (`[0, 1]`, `(0, inf)`).
    pub range: String,
    /// Lower bound (`None`: unbounded).
    pub min: Option<f64>,
    /// Whether `min` is admissible.
    pub min_inclusive: bool,
    /// Upper bound (`None`: unbounded).
    pub max: Option<f64>,
    /// Whether `max` is admissible.
    pub max_inclusive: bool,
    /// Where it appears, when not in every form (`hardening: Voce`, `terms`).
    pub only_in: Vec<String>,
}

/// One form.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FormInfo {
    /// The choices (`hardening: Power, rate: Norton`; empty without kinds).
    pub label: String,
    /// Its parameter names, in the law's order.
    pub parameters: Vec<String>,
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// Where the parameter `name` of `l` comes from, when not from every form.
fn only_in(l: &LawListing, name: &str) -> Vec<String> {
    let stem = name.trim_end_matches(|c: char| c.is_ascii_digit());
    for (field, fields) in &l.lists {
        if stem != name && fields.contains(&stem) {
            return vec![format!("{field} (element {})", &name[stem.len()..])];
        }
    }
    if l.forms_with(name).len() == l.forms.len() {
        return Vec::new();
    }
    let mut out = Vec::new();
    for k in &l.kinds {
        for (v, fields) in &k.variants {
            if fields.contains(&name) {
                out.push(format!("{}: {v}", k.field));
            }
        }
    }
    out
}

fn info(l: &LawListing) -> LawInfo {
    LawInfo {
        name: l.entry.name.into(),
        variant: l.entry.variant.into(),
        summary: l.entry.summary.into(),
        example: l.entry.example.into(),
        kinds: l
            .kinds
            .iter()
            .map(|k| KindInfo {
                field: k.field.into(),
                optional: k.optional,
                variants: k
                    .variants
                    .iter()
                    .map(|(n, f)| VariantInfo {
                        name: (*n).into(),
                        fields: f.iter().map(|s| s.to_string()).collect(),
                    })
                    .collect(),
            })
            .collect(),
        lists: l
            .lists
            .iter()
            .map(|(f, inner)| ListInfo {
                field: (*f).into(),
                fields: inner.iter().map(|s| s.to_string()).collect(),
            })
            .collect(),
        parameters: l
            .params()
            .iter()
            .map(|p| ParamEntry {
                name: p.name.into(),
                set: format!("law.{}", p.name),
                unit: p.unit.into(),
                description: p.description.into(),
                range: p.range_text(),
                min: finite(p.min),
                min_inclusive: p.min_inclusive,
                max: finite(p.max),
                max_inclusive: p.max_inclusive,
                only_in: only_in(l, p.name),
            })
            .collect(),
        forms: l
            .forms
            .iter()
            .map(|f| FormInfo {
                label: f.label.clone(),
                parameters: f.params.iter().map(|p| p.name.to_string()).collect(),
            })
            .collect(),
    }
}

/// Every registered law, in the registry's order.
///
/// # Errors
/// A registered law the catalog cannot build a form of (a defect of that law's entry).
pub fn laws() -> Result<Vec<LawInfo>> {
    let c = catalog::catalog().map_err(|e| {
        Error::msg(
            ErrorKind::Config,
            format!("the laws registry cannot be listed: {e}"),
        )
    })?;
    Ok(c.iter().map(info).collect())
}

/// A configuration law of every form of every registered law (the catalog's placeholder
/// numbers), with the form's label: what a test of `--set law.NAME` runs on.
///
/// # Errors
/// As [`laws`], or a form the configuration layer refuses.
pub fn form_specs() -> Result<Vec<(String, LawSpec)>> {
    let c = catalog::catalog()
        .map_err(|e| Error::msg(ErrorKind::Config, format!("laws registry: {e}")))?;
    let mut out = Vec::new();
    for l in &c {
        for f in &l.forms {
            let spec: Vec<(String, SpecValue)> = f.spec.clone();
            let law = LawSpec::from_fields(l.entry.variant, spec)
                .map_err(|e| Error::msg(ErrorKind::Config, format!("{e:#}")))?;
            out.push((format!("{} {}", l.entry.variant, f.label), law));
        }
    }
    Ok(out)
}

/// The listing as text for a terminal: per law its summary, example, kinds and a table of
/// parameters (name as `--set law.NAME` takes it, unit, range, meaning, where it appears).
pub fn text(laws: &[LawInfo]) -> String {
    let mut s = String::new();
    for l in laws {
        s.push_str(&format!("{} ({}): {}\n", l.variant, l.name, l.summary));
        s.push_str(&format!("  example: {}\n", l.example));
        for k in &l.kinds {
            let vs: Vec<String> = k
                .variants
                .iter()
                .map(|v| format!("{}({})", v.name, v.fields.join(", ")))
                .collect();
            s.push_str(&format!(
                "  {}: {}{}\n",
                k.field,
                if k.optional {
                    "omitted (rate-independent), or "
                } else {
                    "one of "
                },
                vs.join(", ")
            ));
        }
        for li in &l.lists {
            s.push_str(&format!(
                "  {}: a list of ({}), parameters numbered per element ({})\n",
                li.field,
                li.fields.join(", "),
                li.fields
                    .iter()
                    .map(|f| format!("{f}1"))
                    .chain(li.fields.iter().map(|f| format!("{f}2")))
                    .chain(std::iter::once("...".to_string()))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        s.push_str("  parameters (--set law.NAME=VALUE; identify.params.NAME):\n");
        let w = l.parameters.iter().map(|p| p.name.len()).max().unwrap_or(1);
        let wu = l.parameters.iter().map(|p| p.unit.len()).max().unwrap_or(1);
        let wr = l
            .parameters
            .iter()
            .map(|p| p.range.len())
            .max()
            .unwrap_or(1);
        for p in &l.parameters {
            let only = if p.only_in.is_empty() {
                String::new()
            } else {
                format!(" [{}]", p.only_in.join("; "))
            };
            s.push_str(&format!(
                "    {:w$}  {:wu$}  {:wr$}  {}{only}\n",
                p.name, p.unit, p.range, p.description
            ));
        }
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The listing is the registry's: every law, every form's parameters as the built
    /// material declares them, set paths `law.NAME`.
    #[test]
    fn the_listing_is_the_registry() {
        let laws = laws().unwrap();
        let variants: Vec<&str> = laws.iter().map(|l| l.variant.as_str()).collect();
        assert_eq!(variants, indentify_laws::VARIANTS);
        let plastic = &laws[3];
        let q = plastic.parameters.iter().find(|p| p.name == "Q").unwrap();
        assert_eq!(q.only_in, ["hardening: Voce"]);
        assert_eq!(q.set, "law.Q");
        let n = plastic.parameters.iter().find(|p| p.name == "n").unwrap();
        assert_eq!(n.only_in, ["hardening: Power", "hardening: Swift"]);
        let prony = &laws[4];
        let g2 = prony.parameters.iter().find(|p| p.name == "g2").unwrap();
        assert_eq!(g2.only_in, ["terms (element 2)"]);
        assert!(text(&laws).contains("law.NAME"));
    }
}
