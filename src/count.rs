//! Counts as JSON numbers. JSON Schema's `integer` is any number without a fractional part, so
//! `601.0` is as valid a count as `601`; serde reads only the latter into an integer type. The
//! request fields that are counts read both with these helpers (`deserialize_with`), and refuse
//! fractions, negatives and values their type cannot hold with a message that says so.

use serde::Deserialize;
use serde::de::{Deserializer, Error, Visitor};
use std::fmt;

/// A count read from any JSON number with no fractional part.
struct Whole<T>(T);

impl<'de, T: TryFrom<u64>> Deserialize<'de> for Whole<T> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let value = deserializer.deserialize_any(WholeVisitor)?;
        T::try_from(value).map(Whole).map_err(|_| D::Error::custom(format!("{value} is too large for this count")))
    }
}

struct WholeVisitor;

impl Visitor<'_> for WholeVisitor {
    type Value = u64;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a non-negative whole number")
    }

    fn visit_u64<E: Error>(self, v: u64) -> Result<u64, E> {
        Ok(v)
    }

    fn visit_i64<E: Error>(self, v: i64) -> Result<u64, E> {
        u64::try_from(v).map_err(|_| E::custom(format!("expected a non-negative whole number, got {v}")))
    }

    fn visit_f64<E: Error>(self, v: f64) -> Result<u64, E> {
        // 2⁶⁴ is the first float beyond u64; every float below it with no fraction is exact.
        if v.fract() == 0.0 && (0.0..18_446_744_073_709_551_616.0).contains(&v) {
            Ok(v as u64)
        } else {
            Err(E::custom(format!("expected a non-negative whole number, got {v}")))
        }
    }
}

/// `#[serde(deserialize_with = "crate::count::count")]`
pub fn count<'de, D: Deserializer<'de>, T: TryFrom<u64>>(deserializer: D) -> Result<T, D::Error> {
    Whole::<T>::deserialize(deserializer).map(|w| w.0)
}

/// `#[serde(deserialize_with = "crate::count::optional_count")]`: a count or `null`.
pub fn optional_count<'de, D: Deserializer<'de>, T: TryFrom<u64>>(deserializer: D) -> Result<Option<T>, D::Error> {
    Option::<Whole<T>>::deserialize(deserializer).map(|w| w.map(|w| w.0))
}

/// Largest seed: 2⁶³ − 1, the largest `int64`, which is what the API description can state.
const MAX_SEED: u64 = i64::MAX as u64;

/// `#[serde(deserialize_with = "crate::count::seed")]`: a count of at most 2⁶³ − 1.
pub fn seed<'de, D: Deserializer<'de>>(deserializer: D) -> Result<u64, D::Error> {
    let value: u64 = count(deserializer)?;
    if value > MAX_SEED {
        return Err(D::Error::custom(format!("a seed is at most {MAX_SEED}, got {value}")));
    }
    Ok(value)
}

/// `#[serde(deserialize_with = "crate::count::optional_seed")]`: a seed or `null`.
pub fn optional_seed<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Option<u64>, D::Error> {
    match optional_count::<D, u64>(deserializer)? {
        Some(value) if value > MAX_SEED => Err(D::Error::custom(format!("a seed is at most {MAX_SEED}, got {value}"))),
        other => Ok(other),
    }
}

#[cfg(test)]
mod tests {
    #[derive(Debug, serde::Deserialize)]
    struct Counts {
        #[serde(deserialize_with = "super::count")]
        samples: usize,
        #[serde(default, deserialize_with = "super::optional_count")]
        floor: Option<u32>,
    }

    fn read(text: &str) -> Result<Counts, String> {
        serde_json::from_str(text).map_err(|e| e.to_string())
    }

    #[test]
    fn whole_numbers_in_any_spelling_and_nothing_else() {
        let c = read(r#"{"samples": 601.0, "floor": 40}"#).unwrap();
        assert_eq!((c.samples, c.floor), (601, Some(40)));
        assert_eq!(read(r#"{"samples": 6e2}"#).unwrap().samples, 600);
        assert_eq!(read(r#"{"samples": 1, "floor": null}"#).unwrap().floor, None);
        assert!(read(r#"{"samples": 1.5}"#).unwrap_err().contains("whole number, got 1.5"));
        assert!(read(r#"{"samples": -1}"#).unwrap_err().contains("got -1"));
        assert!(read(r#"{"samples": 1, "floor": 5000000000}"#).unwrap_err().contains("too large"));
        assert!(read(r#"{"samples": 1e300}"#).is_err());
        assert!(read(r#"{"samples": "7"}"#).is_err());
    }
}
