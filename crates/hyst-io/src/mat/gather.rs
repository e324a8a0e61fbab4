//! A record's channels gathered from a struct, as data owners save them: one struct (or
//! struct-array element, or cell) per sensor, holding its samples beside its name, units and
//! position; or one struct whose fields are the channels.
//!
//! The rules, applied at every level:
//! - a struct array's elements, and a cell's items, are each a sensor or a group;
//! - a struct is a **sensor** when one of its fields is its data: its only numeric array of
//!   more than [`SHORTEST`] values, else the one named `data`, `values`, `signal` or
//!   `samples`; its channel is named by its char field `name` (or `label`, `id`, `tag`,
//!   `channel`, `sensor`), else by its place (`rec.p1`, `rec(3)`); a data matrix gives one
//!   channel per column, named by a cell of names (`names`, `labels`, `channels`) if it has
//!   as many, else `name(:,k)`;
//! - any other struct is a **group**: each numeric array of more than [`SHORTEST`] values is
//!   a channel named by its field, and its structs and cells are read by these rules;
//! - shorter arrays, text and anything else are the record's description, not channels; a
//!   scalar field `fs` (or `rate`, `sampling_rate`, `sample_rate`, `samplerate`,
//!   `sampling_frequency`, `fsample`) states the sampling rate.
//!
//! Names that repeat are told apart by the sensors' char field `direction` (or `dir`,
//! `axis`), else every channel is named by its place, and a note says so.

use super::Endian;
use super::tree::Node;

/// The fewest values a numeric array holds to be a channel rather than a description (a
/// position holds 2–3, a calibration a few).
pub(super) const SHORTEST: usize = 3;

const DATA: [&str; 4] = ["data", "values", "signal", "samples"];
const NAME: [&str; 6] = ["name", "label", "id", "tag", "channel", "sensor"];
const NAMES: [&str; 3] = ["names", "labels", "channels"];
const DIRECTION: [&str; 3] = ["direction", "dir", "axis"];
const RATE: [&str; 7] = [
    "fs",
    "rate",
    "sampling_rate",
    "sample_rate",
    "samplerate",
    "sampling_frequency",
    "fsample",
];

/// One channel as found: where it is, its sensor's name and direction if it states them,
/// and its samples.
pub(super) struct Channel {
    pub(super) place: String,
    name: Option<String>,
    direction: Option<String>,
    pub(super) values: Vec<f64>,
}

/// What a struct gives: its channels, and the sampling rates its fields state (with where).
#[derive(Default)]
pub(super) struct Gathered {
    pub(super) channels: Vec<Channel>,
    pub(super) rates: Vec<(String, f64)>,
    /// The name of the variable gathered: the place of a 1×1 struct's own data.
    pub(super) root: String,
}

/// Whether `field` is one of `names`, ignoring case.
fn is(field: &str, names: &[&str]) -> bool {
    names.iter().any(|n| n.eq_ignore_ascii_case(field))
}

/// `parent.field`, or `field` at the top.
fn join(parent: &str, field: &str) -> String {
    if parent.is_empty() {
        field.to_string()
    } else {
        format!("{parent}.{field}")
    }
}

/// The numeric arrays long enough to be channels.
fn long(node: &Node) -> bool {
    matches!(node, Node::Numeric(v) if v.rows.saturating_mul(v.columns) > SHORTEST)
}

impl Gathered {
    /// Gather `node`, found at `place` (`root` names the top for a struct array's elements).
    pub(super) fn gather(
        &mut self,
        place: &str,
        node: &Node,
        endian: Endian,
    ) -> Result<(), String> {
        match node {
            Node::Struct { values, fields, .. } if values.len() == 1 => {
                self.structure(place, fields, &values[0], endian)
            }
            Node::Struct { values, fields, .. } => {
                values.iter().enumerate().try_for_each(|(k, v)| {
                    self.structure(&format!("{place}({})", k + 1), fields, v, endian)
                })
            }
            Node::Cell { items, .. } => items.iter().enumerate().try_for_each(|(k, item)| {
                self.gather(&format!("{place}{{{}}}", k + 1), item, endian)
            }),
            Node::Numeric(_) if long(node) => self.array(place, None, None, node, &[], endian),
            _ => Ok(()),
        }
    }

    /// The sampling rate `node` states, if it is a scalar named as a rate is (the last part
    /// of `place`).
    pub(super) fn gather_rate(&mut self, place: &str, node: &Node, endian: Endian) {
        let field = place.rsplit('.').next().unwrap_or(place);
        if let Node::Numeric(n) = node
            && is(field, &RATE)
            && n.rows.saturating_mul(n.columns) == 1
            && !n.complex
        {
            self.rates
                .push((place.to_string(), endian.value(n.code, &n.data, 0)));
        }
    }

    /// One struct's fields: a sensor or a group (see the module's documentation).
    fn structure(
        &mut self,
        place: &str,
        fields: &[String],
        values: &[Node],
        endian: Endian,
    ) -> Result<(), String> {
        let text_of = |names: &[&str]| {
            fields.iter().zip(values).find_map(|(f, v)| match v {
                Node::Text(t) if is(f, names) && !t.is_empty() => Some(t.clone()),
                _ => None,
            })
        };
        for (f, v) in fields.iter().zip(values) {
            self.gather_rate(&join(place, f), v, endian);
        }
        let candidates: Vec<usize> = (0..fields.len()).filter(|&i| long(&values[i])).collect();
        let data = match candidates.as_slice() {
            [one] => Some(*one),
            several => several.iter().copied().find(|&i| is(&fields[i], &DATA)),
        };
        if let Some(d) = data {
            let labels: Vec<String> = fields
                .iter()
                .zip(values)
                .find_map(|(f, v)| match v {
                    Node::Cell { items, .. } if is(f, &NAMES) => Some(
                        items
                            .iter()
                            .map(|i| match i {
                                Node::Text(t) => t.clone(),
                                _ => String::new(),
                            })
                            .collect(),
                    ),
                    _ => None,
                })
                .unwrap_or_default();
            self.array(
                place,
                text_of(&NAME),
                text_of(&DIRECTION),
                &values[d],
                &labels,
                endian,
            )?;
        }
        for (i, (f, v)) in fields.iter().zip(values).enumerate() {
            match v {
                _ if Some(i) == data => {}
                Node::Numeric(_) if data.is_none() && long(v) => {
                    self.array(&join(place, f), None, None, v, &[], endian)?
                }
                Node::Struct { .. } | Node::Cell { .. } => {
                    self.gather(&join(place, f), v, endian)?
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The channels of one numeric array: a vector is one; a matrix's columns are each one.
    fn array(
        &mut self,
        place: &str,
        name: Option<String>,
        direction: Option<String>,
        node: &Node,
        labels: &[String],
        endian: Endian,
    ) -> Result<(), String> {
        let Node::Numeric(v) = node else {
            return Ok(());
        };
        let root = self.root.clone();
        let place = if place.is_empty() { &root } else { place };
        if v.complex {
            return Err(format!("`{place}` is complex; a record is real"));
        }
        if v.ndims > 2 {
            return Err(format!(
                "`{place}` has {} dimensions; a channel is a vector of samples",
                v.ndims
            ));
        }
        let (n, l) = if v.rows == 1 || v.columns == 1 {
            (v.rows * v.columns, 1)
        } else {
            (v.rows, v.columns)
        };
        if l > n {
            return Err(format!(
                "`{place}` is {} × {}; a record is samples × channels, so this looks transposed",
                v.rows, v.columns
            ));
        }
        for c in 0..l {
            let values = (0..n)
                .map(|s| endian.value(v.code, &v.data, c * n + s))
                .collect();
            let (place, name) = if l == 1 {
                (place.to_string(), name.clone())
            } else {
                let label = labels.get(c).filter(|s| !s.is_empty()).cloned();
                let base = name.clone().unwrap_or_else(|| place.to_string());
                (
                    format!("{place}(:,{})", c + 1),
                    Some(label.unwrap_or_else(|| format!("{base}(:,{})", c + 1))),
                )
            };
            self.channels.push(Channel {
                place,
                name,
                direction: direction.clone(),
                values,
            });
        }
        Ok(())
    }
}

/// The channels' names: the sensors' own where they are unique, told apart by direction
/// where that makes them so, else every channel's place; with the note to give when the
/// names were not the sensors' own.
pub(super) fn names(channels: &[Channel]) -> (Vec<String>, Option<String>) {
    let unique = |names: &[String]| {
        let mut sorted: Vec<&String> = names.iter().collect();
        sorted.sort();
        sorted.windows(2).all(|w| w[0] != w[1]) && names.iter().all(|n| !n.is_empty())
    };
    let own: Vec<String> = channels
        .iter()
        .map(|c| c.name.clone().unwrap_or_else(|| c.place.clone()))
        .collect();
    if unique(&own) {
        return (own, None);
    }
    let directed: Vec<String> = channels
        .iter()
        .zip(&own)
        .map(|(c, n)| match &c.direction {
            Some(d) if c.name.is_some() => format!("{n}_{d}"),
            _ => n.clone(),
        })
        .collect();
    if unique(&directed) {
        return (directed, None);
    }
    let places: Vec<String> = channels.iter().map(|c| c.place.clone()).collect();
    let repeated = own
        .iter()
        .enumerate()
        .find(|(i, n)| own[..*i].contains(n))
        .map_or(String::new(), |(_, n)| n.clone());
    (
        places,
        Some(format!(
            "sensor names repeat (`{repeated}`), so the channels are named by their place in the struct"
        )),
    )
}
