//! Fixed-length lists in task files, read strictly: `count = [0, 4, 9]` is an
//! error naming the length, where the TOML reader on its own would keep the
//! first two numbers and drop the rest without a word.

use serde::de::{Deserialize, Deserializer, Error};
use std::collections::BTreeMap;

fn exact<T, const N: usize, E: Error>(v: Vec<T>) -> Result<[T; N], E> {
    let len = v.len();
    v.try_into().map_err(|_| E::invalid_length(len, &format!("a list of exactly {N}").as_str()))
}

/// `[T; N]`, refusing a list of another length.
///
/// # Errors
/// A list of another length, or what reading `T` reports.
pub fn array<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(d: D) -> Result<[T; N], D::Error> {
    exact(Vec::<T>::deserialize(d)?)
}

/// `Option<[T; N]>`, refusing a list of another length.
///
/// # Errors
/// As [`array`].
pub fn option<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
    d: D,
) -> Result<Option<[T; N]>, D::Error> {
    Option::<Vec<T>>::deserialize(d)?.map(exact).transpose()
}

/// A table of `[T; N]` by name, refusing a list of another length.
///
/// # Errors
/// As [`array`].
pub fn map<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
    d: D,
) -> Result<BTreeMap<String, [T; N]>, D::Error> {
    BTreeMap::<String, Vec<T>>::deserialize(d)?.into_iter().map(|(k, v)| Ok((k, exact(v)?))).collect()
}

#[cfg(test)]
mod tests {
    #[derive(Debug, serde::Deserialize)]
    struct Probe {
        #[serde(deserialize_with = "super::array")]
        pair: [usize; 2],
        #[serde(default, deserialize_with = "super::option")]
        maybe: Option<[f64; 3]>,
    }

    #[test]
    fn a_list_of_another_length_is_an_error() {
        let ok: Probe = toml::from_str("pair = [0, 4]\nmaybe = [1.0, 2.0, 3.0]").unwrap();
        assert_eq!((ok.pair, ok.maybe), ([0, 4], Some([1.0, 2.0, 3.0])));
        let e = toml::from_str::<Probe>("pair = [0, 4, 9]").unwrap_err().to_string();
        assert!(e.contains("invalid length 3, expected a list of exactly 2"), "{e}");
        let e = toml::from_str::<Probe>("pair = [0, 4]\nmaybe = [1.0]").unwrap_err().to_string();
        assert!(e.contains("invalid length 1, expected a list of exactly 3"), "{e}");
        assert!(toml::from_str::<Probe>("pair = [0, 4]").unwrap().maybe.is_none());
    }
}
