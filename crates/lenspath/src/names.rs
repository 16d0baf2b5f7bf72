//! Choices that every front end names by the same words (a sampler, an
//! integrator, a focus measure, a colour filter array...): one table of
//! values and names per type, one way to parse a name, one error message.
//! The CLI's value lists, scene files, Python's keywords and the viewer all
//! read them here.

use crate::error::{Error, Result};

/// A value chosen by name from a fixed list.
pub trait Named: Copy + PartialEq + 'static {
    /// What a value is, as an error names it ("sampler", "tone curve").
    const WHAT: &'static str;

    /// Every value with its name, in the order front ends list them.
    const NAMED: &'static [(Self, &'static str)];

    /// Its name: its variant's in [`Named::NAMED`], whatever the variant's
    /// fields hold (a strategy's patience, a measure's step).
    fn name(self) -> &'static str {
        let variant = std::mem::discriminant(&self);
        Self::NAMED
            .iter()
            .find(|(value, _)| std::mem::discriminant(value) == variant)
            .map_or("", |(_, name)| name)
    }

    /// Every name, in [`Named::NAMED`]'s order.
    fn names() -> Vec<&'static str> {
        Self::NAMED.iter().map(|(_, name)| *name).collect()
    }

    /// The value called `name` (any case); fails with
    /// "unknown WHAT 'name'; use one of a, b, c".
    fn parse(name: &str) -> Result<Self> {
        Self::NAMED
            .iter()
            .find(|(_, n)| n.eq_ignore_ascii_case(name))
            .map(|(value, _)| *value)
            .ok_or_else(|| {
                Error::InvalidArgument(format!(
                    "unknown {} '{name}'; use one of {}",
                    Self::WHAT,
                    Self::names().join(", ")
                ))
            })
    }
}

/// Reads a [`Named`] value from its name, for `#[serde(deserialize_with)]`:
/// a JSON request names its choices as the CLI does, failing with
/// [`Named::parse`]'s message.
pub fn deserialize<'de, D: serde::Deserializer<'de>, T: Named>(deserializer: D) -> std::result::Result<T, D::Error> {
    let name = <std::borrow::Cow<'de, str> as serde::Deserialize>::deserialize(deserializer)?;
    T::parse(&name).map_err(serde::de::Error::custom)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Fruit {
        Apple,
        Pear,
    }

    impl Named for Fruit {
        const WHAT: &'static str = "fruit";
        const NAMED: &'static [(Fruit, &'static str)] = &[(Fruit::Apple, "apple"), (Fruit::Pear, "pear")];
    }

    #[test]
    fn names_parse_both_ways_and_an_unknown_one_lists_them() {
        for &(value, name) in Fruit::NAMED {
            assert_eq!(Fruit::parse(name).unwrap(), value);
            assert_eq!(value.name(), name);
        }
        assert_eq!(Fruit::parse("PEAR").unwrap(), Fruit::Pear);
        let err = Fruit::parse("plum").unwrap_err().to_string();
        assert_eq!(err, "unknown fruit 'plum'; use one of apple, pear");
    }
}
