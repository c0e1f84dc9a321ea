//! Fixed-size arrays read from files with their length checked: serde's own
//! `[T; N]` takes the first `N` values of a longer list from some formats
//! (TOML among them) and drops the rest, so `translation = [0, 0, 0, 5]`
//! would be read as `[0, 0, 0]`. Fields use these with
//! `#[serde(deserialize_with = "geom::exact::array")]`.
//!
//! ```
//! #[derive(Debug, serde::Deserialize)]
//! struct Pose {
//!     #[serde(deserialize_with = "geom::exact::array")]
//!     translation: [f64; 3],
//! }
//! let ok: Pose = serde_json::from_str(r#"{"translation": [1, 2, 3]}"#).unwrap();
//! assert_eq!(ok.translation, [1.0, 2.0, 3.0]);
//! let long = serde_json::from_str::<Pose>(r#"{"translation": [1, 2, 3, 4]}"#);
//! assert!(long.unwrap_err().to_string().contains("expected exactly 3 values"));
//! ```

use serde::de::{Deserialize, Deserializer, Error};

/// What a list of `N` values was expected to be.
struct Exactly(usize);

impl serde::de::Expected for Exactly {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "exactly {} values", self.0)
    }
}

fn exact<T, E: Error, const N: usize>(v: Vec<T>) -> Result<[T; N], E> {
    let len = v.len();
    v.try_into()
        .map_err(|_| E::invalid_length(len, &Exactly(N)))
}

/// `[T; N]` from a list of exactly `N` values.
pub fn array<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    exact(Vec::<T>::deserialize(d)?)
}

/// A list of `[T; N]`, each of exactly `N` values.
pub fn vec_of_arrays<'de, D, T, const N: usize>(d: D) -> Result<Vec<[T; N]>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    Vec::<Vec<T>>::deserialize(d)?
        .into_iter()
        .map(exact)
        .collect()
}

/// A list of lists of `[T; N]`, each of exactly `N` values.
pub fn vec_of_vec_of_arrays<'de, D, T, const N: usize>(d: D) -> Result<Vec<Vec<[T; N]>>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    Vec::<Vec<Vec<T>>>::deserialize(d)?
        .into_iter()
        .map(|inner| inner.into_iter().map(exact).collect())
        .collect()
}
