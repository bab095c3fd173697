//! The `law` of a configuration, read and written through the laws crate's registry
//! (`indentify_laws::registry`): every law, old and new, is parsed by one schema-driven
//! deserializer (nested variant names such as `hardening: Power(n: 0.2)` included, which a
//! generic `ron::Value` would drop), built by the registry's constructor, and reached by
//! `--set law.<parameter>` with the registry's parameter names (`E`, `nu`, `sY`, `n`, `Q`,
//! `K`, `m`, `g1`, `tau1`, ...). Adding a law to the registry adds it here with no edit.

use std::fmt;
use std::sync::Arc;

use anyhow::{Result, anyhow};
use indentify_laws::registry::{
    self, FieldKind, FieldSchema, LawEntry, REGISTRY, SpecValue, VARIANTS, VariantSchema,
};
use indentify_laws::{LawError, Material, ParamInfo};
use serde::de::{self, DeserializeSeed, EnumAccess, MapAccess, SeqAccess, VariantAccess, Visitor};
use serde::ser::{SerializeSeq, SerializeStruct, SerializeStructVariant, SerializeTuple};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A law and its specification, as written in a configuration
/// (`Plastic(E: .., nu: .., sY: .., hardening: Power(n: 0.2), rate: Norton(K: .., m: ..))`),
/// checked by the registry when read.
#[derive(Clone, Debug)]
pub struct LawSpec {
    entry: &'static LawEntry,
    fields: Vec<(String, SpecValue)>,
}

impl PartialEq for LawSpec {
    fn eq(&self, other: &Self) -> bool {
        self.entry.variant == other.entry.variant && self.fields == other.fields
    }
}

/// A material built from a configuration: the registry's material and its parameters in
/// the order of `material.params()`.
#[derive(Debug)]
pub struct BuiltLaw {
    /// The material.
    pub material: Box<dyn Material>,
    /// Its parameter values, range-checked.
    pub params: Vec<f64>,
}

impl LawSpec {
    /// A law whose fields are all numbers (`Elastic`, `Maxwell`, `NortonHoff`), from
    /// `(field, value)` pairs; checked by the registry.
    ///
    /// # Errors
    /// An unknown variant, or fields the registry refuses.
    pub fn numbers(variant: &str, values: &[(&str, f64)]) -> Result<LawSpec> {
        let fields = values
            .iter()
            .map(|&(n, v)| (n.to_string(), SpecValue::Number(v)))
            .collect();
        LawSpec::from_fields(variant, fields)
    }

    /// A law from its variant (or name) and fields, checked by the registry.
    ///
    /// # Errors
    /// An unknown variant, or fields the registry refuses (naming the field and range).
    pub fn from_fields(variant: &str, fields: Vec<(String, SpecValue)>) -> Result<LawSpec> {
        let entry = registry::entry(variant).ok_or_else(|| {
            anyhow!(
                "unknown law `{variant}`; registered: {}",
                VARIANTS.join(", ")
            )
        })?;
        let spec = LawSpec { entry, fields };
        spec.material()?;
        Ok(spec)
    }

    /// The law's name in reports (`elastic`, `plastic`, `prony`).
    pub fn name(&self) -> &'static str {
        self.entry.name
    }

    /// The configuration variant (`Elastic`, `Plastic`, `Prony`).
    pub fn variant(&self) -> &'static str {
        self.entry.variant
    }

    /// The registry entry.
    pub fn entry(&self) -> &'static LawEntry {
        self.entry
    }

    /// The fields as written.
    pub fn fields(&self) -> &[(String, SpecValue)] {
        &self.fields
    }

    /// The registry's material and its parameter vector.
    ///
    /// # Errors
    /// What the registry refuses, as `law.<field>: ...` (a value outside its range names the
    /// range, unit and meaning).
    pub fn material(&self) -> Result<BuiltLaw> {
        match registry::build(self.entry.variant, &self.fields) {
            Ok(b) => Ok(BuiltLaw {
                material: b.material,
                params: b.params,
            }),
            Err(e) => Err(anyhow!(law_error_text(&e, None))),
        }
    }

    /// `(name, value)` of every parameter, in the material's order (`E`, `nu`, `sY`, `n`,
    /// `K`, `m`; `g1`, `tau1`, ...).
    pub fn named_params(&self) -> Vec<(&'static str, f64)> {
        self.material()
            .map(|b| {
                b.material
                    .params()
                    .iter()
                    .map(|p| p.name)
                    .zip(b.params)
                    .collect()
            })
            .unwrap_or_default()
    }

    /// The parameter descriptions of the material (empty if the law does not build).
    pub fn param_infos(&self) -> Vec<ParamInfo> {
        self.material()
            .map(|b| b.material.params().to_vec())
            .unwrap_or_default()
    }

    /// The material the solver, the adjoint and `identify::Problem` take, shared, and its
    /// parameters. Every law goes through here: a stress-only law is the registry's
    /// `LawMaterial` (the solver dispatches it to the `Law` fast paths through
    /// `Material::as_law`, so its bits are unchanged), a law with internal variables
    /// (`Plastic`, `Prony`) its own material.
    ///
    /// # Errors
    /// As [`LawSpec::material`].
    pub fn build(&self) -> Result<(Arc<dyn Material>, Vec<f64>)> {
        let b = self.material()?;
        Ok((Arc::from(b.material), b.params))
    }

    /// Sets the parameter `name` (a number anywhere in the fields, e.g. `E`, `sY`, `K`) to
    /// `value`; `false` when the law has no such number field. The caller checks the law
    /// again ([`LawSpec::material`]) before using it.
    pub fn set_number(&mut self, name: &str, value: f64) -> bool {
        set_number_in(&mut self.fields, name, value)
    }

    /// The dotted path below `law` of the parameter `name` (`n` -> `hardening.n`, `K` ->
    /// `rate.K`, `g2` -> `terms.1.g`), or `None` when the law has no such parameter.
    pub fn param_path(&self, name: &str) -> Option<String> {
        if let Some(p) = find_number(&self.fields, name, "") {
            return Some(p);
        }
        let stem = name.trim_end_matches(|c: char| c.is_ascii_digit());
        let k: usize = name[stem.len()..].parse().ok()?;
        for (field, v) in &self.fields {
            if let SpecValue::List(items) = v {
                if let Some(SpecValue::Variant { fields, .. }) = items.get(k.checked_sub(1)?) {
                    if fields.iter().any(|(n, _)| n == stem) {
                        return Some(format!("{field}.{}.{stem}", k - 1));
                    }
                }
            }
        }
        None
    }
}

/// A law error as one line naming the field (`law.hardening.n`), the value and the range.
fn law_error_text(e: &LawError, law: Option<&dyn Material>) -> String {
    match e {
        LawError::Parameter {
            law: l,
            name,
            value,
            range,
        } => {
            let what = law
                .and_then(|m| m.params().iter().find(|i| i.name == *name))
                .map_or(String::new(), |i| {
                    format!(" ({}, {})", i.description, i.unit)
                });
            format!(
                "law.{name} = {value} is not allowed: expected a value in {range}{what} (law \
                 `{l}`)"
            )
        }
        LawError::Spec {
            law,
            field,
            message,
        } => {
            format!("law.{field}: {message} (law `{law}`)")
        }
        other => format!("law: {other}"),
    }
}

/// The dotted path of the number field `name` in `fields` (nested variants searched).
fn set_number_in(fields: &mut [(String, SpecValue)], name: &str, value: f64) -> bool {
    for (n, v) in fields.iter_mut() {
        let found = match v {
            SpecValue::Number(x) if n == name => {
                *x = value;
                true
            }
            SpecValue::Variant { name: vn, fields } if !vn.is_empty() => {
                set_number_in(fields, name, value)
            }
            _ => false,
        };
        if found {
            return true;
        }
    }
    false
}

fn find_number(fields: &[(String, SpecValue)], name: &str, prefix: &str) -> Option<String> {
    for (n, v) in fields {
        match v {
            SpecValue::Number(_) if n == name => return Some(format!("{prefix}{n}")),
            SpecValue::Variant { name: vn, fields } if !vn.is_empty() => {
                if let Some(p) = find_number(fields, name, &format!("{prefix}{n}.")) {
                    return Some(p);
                }
            }
            _ => {}
        }
    }
    None
}

// ---------------------------------------------------------------- deserialization

impl<'de> Deserialize<'de> for LawSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<LawSpec, D::Error> {
        d.deserialize_enum("law", VARIANTS, LawVisitor)
    }
}

struct LawVisitor;

/// A variant or field name, read as an identifier (RON writes them bare, JSON as keys).
struct Ident(String);

impl<'de> Deserialize<'de> for Ident {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Ident, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Ident;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "a name")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Ident, E> {
                Ok(Ident(v.to_string()))
            }
        }
        d.deserialize_identifier(V)
    }
}

impl<'de> Visitor<'de> for LawVisitor {
    type Value = LawSpec;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "a law, one of {}", VARIANTS.join(", "))
    }
    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<LawSpec, A::Error> {
        let (Ident(name), variant) = data.variant()?;
        let entry = REGISTRY
            .iter()
            .find(|e| e.variant == name)
            .ok_or_else(|| de::Error::unknown_variant(&name, VARIANTS))?;
        let fields = variant.struct_variant(
            &[],
            FieldsVisitor {
                schema: entry.fields,
                path: String::new(),
            },
        )?;
        let spec = LawSpec { entry, fields };
        match registry::build(entry.variant, &spec.fields) {
            Ok(_) => Ok(spec),
            Err(e) => Err(de::Error::custom(law_error_text(&e, None))),
        }
    }
}

/// Reads the named fields of a variant (or anonymous struct) against its schema.
struct FieldsVisitor {
    schema: &'static [FieldSchema],
    path: String,
}

fn accepted(schema: &[FieldSchema]) -> String {
    schema.iter().map(|f| f.name).collect::<Vec<_>>().join(", ")
}

impl<'de> Visitor<'de> for FieldsVisitor {
    type Value = Vec<(String, SpecValue)>;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "the fields {}", accepted(self.schema))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let mut out: Vec<(String, SpecValue)> = Vec::new();
        while let Some(Ident(key)) = map.next_key::<Ident>()? {
            let Some(field) = self.schema.iter().find(|f| f.name == key) else {
                return Err(de::Error::custom(format!(
                    "law.{}{key}: unknown field; accepted: {}",
                    self.path,
                    accepted(self.schema)
                )));
            };
            if out.iter().any(|(n, _)| *n == key) {
                return Err(de::Error::custom(format!(
                    "law.{}{key}: given twice",
                    self.path
                )));
            }
            let v = map.next_value_seed(KindSeed {
                kind: field.kind,
                path: format!("{}{key}", self.path),
            })?;
            out.push((key, v));
        }
        if let Some(f) = self
            .schema
            .iter()
            .find(|f| !f.optional && !out.iter().any(|(n, _)| n == f.name))
        {
            return Err(de::Error::custom(format!(
                "law.{}{}: missing: a required field (the fields are {})",
                self.path,
                f.name,
                accepted(self.schema)
            )));
        }
        // the schema's order, whatever order the text (or a JSON object) gave
        out.sort_by_key(|(n, _)| self.schema.iter().position(|f| f.name == n));
        Ok(out)
    }
}

/// Reads one value of the shape `kind`.
struct KindSeed {
    kind: FieldKind,
    path: String,
}

impl<'de> DeserializeSeed<'de> for KindSeed {
    type Value = SpecValue;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<SpecValue, D::Error> {
        match self.kind {
            FieldKind::Number => {
                let v = f64::deserialize(d).map_err(|e| {
                    de::Error::custom(format!("law.{}: expected a number ({e})", self.path))
                })?;
                Ok(SpecValue::Number(v))
            }
            FieldKind::OneOf(variants) => d.deserialize_enum(
                "",
                &[],
                OneOfVisitor {
                    variants,
                    path: self.path,
                },
            ),
            FieldKind::ListOf(inner) => d.deserialize_seq(ListVisitor {
                inner: Some(inner),
                path: self.path,
            }),
            FieldKind::Pairs => d.deserialize_seq(ListVisitor {
                inner: None,
                path: self.path,
            }),
        }
    }
}

struct OneOfVisitor {
    variants: &'static [VariantSchema],
    path: String,
}

impl<'de> Visitor<'de> for OneOfVisitor {
    type Value = SpecValue;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = self.variants.iter().map(|v| v.name).collect();
        write!(f, "one of {}", names.join(", "))
    }
    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<SpecValue, A::Error> {
        let (Ident(name), variant) = data.variant()?;
        let Some(v) = self.variants.iter().find(|v| v.name == name) else {
            let names: Vec<&str> = self.variants.iter().map(|v| v.name).collect();
            return Err(de::Error::custom(format!(
                "law.{}: unknown kind `{name}`; expected one of {}",
                self.path,
                names.join(", ")
            )));
        };
        let fields = variant.struct_variant(
            &[],
            FieldsVisitor {
                schema: v.fields,
                path: format!("{}.", self.path),
            },
        )?;
        Ok(SpecValue::Variant { name, fields })
    }
}

/// A list of anonymous structs (`inner`) or of number pairs (`None`).
struct ListVisitor {
    inner: Option<&'static [FieldSchema]>,
    path: String,
}

struct ItemSeed {
    inner: Option<&'static [FieldSchema]>,
    path: String,
}

impl<'de> DeserializeSeed<'de> for ItemSeed {
    type Value = SpecValue;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<SpecValue, D::Error> {
        match self.inner {
            Some(schema) => {
                let fields = d.deserialize_struct(
                    "",
                    &[],
                    FieldsVisitor {
                        schema,
                        path: format!("{}.", self.path),
                    },
                )?;
                Ok(SpecValue::Variant {
                    name: String::new(),
                    fields,
                })
            }
            None => {
                let (a, b) = <(f64, f64)>::deserialize(d).map_err(|e| {
                    de::Error::custom(format!(
                        "law.{}: expected a pair of numbers (eps_p, sigma) ({e})",
                        self.path
                    ))
                })?;
                Ok(SpecValue::Tuple(vec![
                    SpecValue::Number(a),
                    SpecValue::Number(b),
                ]))
            }
        }
    }
}

impl<'de> Visitor<'de> for ListVisitor {
    type Value = SpecValue;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "a list")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<SpecValue, A::Error> {
        let mut items = Vec::new();
        while let Some(v) = seq.next_element_seed(ItemSeed {
            inner: self.inner,
            path: format!("{}.{}", self.path, items.len()),
        })? {
            items.push(v);
        }
        Ok(SpecValue::List(items))
    }
}

// ---------------------------------------------------------------- serialization

impl Serialize for LawSpec {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let index = REGISTRY
            .iter()
            .position(|e| e.variant == self.entry.variant)
            .unwrap_or(0);
        let mut sv =
            s.serialize_struct_variant("law", index as u32, self.entry.variant, self.fields.len())?;
        for (name, value) in &self.fields {
            let Some(field) = self.entry.fields.iter().find(|f| f.name == name) else {
                continue;
            };
            sv.serialize_field(
                field.name,
                &Shaped {
                    kind: field.kind,
                    value,
                },
            )?;
        }
        sv.end()
    }
}

/// A value with its schema, so names written are the schema's static ones.
struct Shaped<'a> {
    kind: FieldKind,
    value: &'a SpecValue,
}

/// Named fields with their schema.
struct ShapedFields<'a> {
    schema: &'static [FieldSchema],
    fields: &'a [(String, SpecValue)],
}

impl ShapedFields<'_> {
    fn each(&self) -> impl Iterator<Item = (&'static FieldSchema, &SpecValue)> {
        self.fields
            .iter()
            .filter_map(|(n, v)| self.schema.iter().find(|f| f.name == n).map(|f| (f, v)))
    }
}

impl Serialize for Shaped<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match (self.kind, self.value) {
            (_, SpecValue::Number(v)) => s.serialize_f64(*v),
            (FieldKind::OneOf(variants), SpecValue::Variant { name, fields }) => {
                let (i, v) = variants
                    .iter()
                    .enumerate()
                    .find(|(_, v)| v.name == name)
                    .ok_or_else(|| serde::ser::Error::custom(format!("unknown kind {name}")))?;
                let shaped = ShapedFields {
                    schema: v.fields,
                    fields,
                };
                let mut sv =
                    s.serialize_struct_variant("kind", i as u32, v.name, shaped.each().count())?;
                for (f, value) in shaped.each() {
                    sv.serialize_field(
                        f.name,
                        &Shaped {
                            kind: f.kind,
                            value,
                        },
                    )?;
                }
                sv.end()
            }
            (FieldKind::ListOf(inner), SpecValue::List(items)) => {
                let mut seq = s.serialize_seq(Some(items.len()))?;
                for item in items {
                    let SpecValue::Variant { fields, .. } = item else {
                        return Err(serde::ser::Error::custom("expected a struct in the list"));
                    };
                    seq.serialize_element(&AnonStruct(ShapedFields {
                        schema: inner,
                        fields,
                    }))?;
                }
                seq.end()
            }
            (_, SpecValue::List(items)) => {
                let mut seq = s.serialize_seq(Some(items.len()))?;
                for item in items {
                    seq.serialize_element(&Shaped {
                        kind: FieldKind::Number,
                        value: item,
                    })?;
                }
                seq.end()
            }
            (_, SpecValue::Tuple(items)) => {
                let mut t = s.serialize_tuple(items.len())?;
                for item in items {
                    t.serialize_element(&Shaped {
                        kind: FieldKind::Number,
                        value: item,
                    })?;
                }
                t.end()
            }
            (_, SpecValue::Variant { .. }) => Err(serde::ser::Error::custom(
                "a variant where the schema has none",
            )),
        }
    }
}

struct AnonStruct<'a>(ShapedFields<'a>);

impl Serialize for AnonStruct<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut st = s.serialize_struct("item", self.0.each().count())?;
        for (f, value) in self.0.each() {
            st.serialize_field(
                f.name,
                &Shaped {
                    kind: f.kind,
                    value,
                },
            )?;
        }
        st.end()
    }
}

// ---------------------------------------------------------------- templates

/// Every registered law as `Variant(field, ...)` (`Plastic(E, nu, sY, hardening, rate)`).
pub fn law_forms() -> Vec<String> {
    REGISTRY
        .iter()
        .map(|e| {
            let names: Vec<&str> = e.fields.iter().map(|f| f.name).collect();
            format!("{}({})", e.variant, names.join(", "))
        })
        .collect()
}

impl LawSpec {
    /// The law's fields as configuration lines (`sY: 300.0,`, `hardening: Power(n: 0.2),`)
    /// with a comment each: the parameters' meaning, unit and range.
    pub fn lines(&self) -> Vec<(String, String)> {
        let infos = self.param_infos();
        let note = |name: &str| {
            infos.iter().find(|i| i.name == name).map_or_else(
                || "(no metadata in indentify_laws)".to_string(),
                |i| format!("{} ({}), in {}", i.description, i.unit, i.range_text()),
            )
        };
        self.fields
            .iter()
            .map(|(name, v)| {
                let comment = match v {
                    SpecValue::Number(_) => note(name),
                    SpecValue::Variant { name: kind, fields } => {
                        let parts: Vec<String> = fields
                            .iter()
                            .map(|(n, _)| format!("{n}: {}", note(n)))
                            .collect();
                        if parts.is_empty() {
                            format!("{name} {kind}")
                        } else {
                            parts.join("; ")
                        }
                    }
                    SpecValue::List(items) => {
                        let kinds = self
                            .entry
                            .fields
                            .iter()
                            .find(|f| f.name == name)
                            .map(|f| f.kind);
                        match kinds {
                            Some(FieldKind::ListOf(_)) => format!(
                                "{} terms; parameters {}",
                                items.len(),
                                infos
                                    .iter()
                                    .skip(2)
                                    .map(|i| i.name)
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ),
                            _ => format!("{} points", items.len()),
                        }
                    }
                    SpecValue::Tuple(_) => String::new(),
                };
                (format!("{name}: {},", spec_text(v)), comment)
            })
            .collect()
    }
}

/// A specification value as RON text.
pub fn spec_text(v: &SpecValue) -> String {
    let num = |x: f64| {
        let s = format!("{x:?}");
        if s.contains(['.', 'e', 'E', 'N', 'i']) {
            s
        } else {
            format!("{s}.0")
        }
    };
    let fields = |fs: &[(String, SpecValue)]| {
        fs.iter()
            .map(|(n, v)| format!("{n}: {}", spec_text(v)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    match v {
        SpecValue::Number(x) => num(*x),
        SpecValue::Variant { name, fields: fs } => format!("{name}({})", fields(fs)),
        SpecValue::List(items) => format!(
            "[{}]",
            items.iter().map(spec_text).collect::<Vec<_>>().join(", ")
        ),
        SpecValue::Tuple(items) => format!(
            "({})",
            items.iter().map(spec_text).collect::<Vec<_>>().join(", ")
        ),
    }
}
