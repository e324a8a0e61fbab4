//! Numbers JSON cannot hold (NaN, ±∞) written as `null` and read back as NaN (feature
//! `serde`): the standard errors a singular Fisher information leaves undefined, the ΔBIC
//! of a rejected candidate, the ε of an unknown noise level. Used by
//! `#[serde(with = "crate::nullable")]` on such fields, so that every report reads back.

use serde::{Deserialize, Deserializer, Serialize, Serializer, de::DeserializeOwned};

/// A value whose numbers may be NaN or infinite, and its JSON form.
pub(crate) trait Nullable: Sized {
    /// The JSON form: `Option<f64>` for each number.
    type Repr: Serialize + DeserializeOwned;
    fn to_repr(&self) -> Self::Repr;
    fn from_repr(r: Self::Repr) -> Result<Self, String>;
}

impl Nullable for f64 {
    type Repr = Option<f64>;
    fn to_repr(&self) -> Option<f64> {
        self.is_finite().then_some(*self)
    }
    fn from_repr(r: Option<f64>) -> Result<f64, String> {
        Ok(r.unwrap_or(f64::NAN))
    }
}

impl<T: Nullable> Nullable for Vec<T> {
    type Repr = Vec<T::Repr>;
    fn to_repr(&self) -> Self::Repr {
        self.iter().map(T::to_repr).collect()
    }
    fn from_repr(r: Self::Repr) -> Result<Self, String> {
        r.into_iter().map(T::from_repr).collect()
    }
}

impl<T: Nullable, const N: usize> Nullable for [T; N] {
    type Repr = Vec<T::Repr>;
    fn to_repr(&self) -> Self::Repr {
        self.iter().map(T::to_repr).collect()
    }
    fn from_repr(r: Self::Repr) -> Result<Self, String> {
        let len = r.len();
        let v: Vec<T> = r.into_iter().map(T::from_repr).collect::<Result<_, _>>()?;
        v.try_into()
            .map_err(|_| format!("expected {N} numbers, got {len}"))
    }
}

impl<A: Nullable, B: Nullable> Nullable for (A, B) {
    type Repr = (A::Repr, B::Repr);
    fn to_repr(&self) -> Self::Repr {
        (self.0.to_repr(), self.1.to_repr())
    }
    fn from_repr(r: Self::Repr) -> Result<Self, String> {
        Ok((A::from_repr(r.0)?, B::from_repr(r.1)?))
    }
}

pub(crate) fn serialize<T: Nullable, S: Serializer>(v: &T, s: S) -> Result<S::Ok, S::Error> {
    v.to_repr().serialize(s)
}

pub(crate) fn deserialize<'de, T: Nullable, D: Deserializer<'de>>(d: D) -> Result<T, D::Error> {
    T::from_repr(T::Repr::deserialize(d)?).map_err(serde::de::Error::custom)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Serialize, Deserialize)]
    struct Fields {
        #[serde(with = "super")]
        x: f64,
        #[serde(with = "super")]
        a: [f64; 2],
        #[serde(with = "super")]
        v: Vec<f64>,
        #[serde(with = "super")]
        t: (f64, f64),
    }

    /// NaN and ±∞ go out as null and come back as NaN; finite numbers come back as they
    /// were; an array of the wrong length is an error naming both lengths.
    #[test]
    fn non_finite_numbers_are_null_and_read_back() {
        let f = Fields {
            x: f64::INFINITY,
            a: [1.5, f64::NAN],
            v: vec![f64::NEG_INFINITY, 2.0],
            t: (3.0, f64::NAN),
        };
        let text = serde_json::to_string(&f).unwrap();
        assert_eq!(
            text,
            r#"{"x":null,"a":[1.5,null],"v":[null,2.0],"t":[3.0,null]}"#
        );
        let back: Fields = serde_json::from_str(&text).unwrap();
        assert!(back.x.is_nan() && back.a[1].is_nan() && back.v[0].is_nan() && back.t.1.is_nan());
        assert_eq!((back.a[0], back.v[1], back.t.0), (1.5, 2.0, 3.0));
        let e = serde_json::from_str::<Fields>(r#"{"x":1,"a":[1],"v":[],"t":[1,2]}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("expected 2 numbers, got 1"), "{e}");
    }
}
