//! [`InNetOrder`]: values per place or per transition, by name, kept in net order.

use serde::Serialize;
use serde::ser::SerializeMap;

/// Values by place or transition name, in the net's order (`p1, p2, …, p10`, not `p1, p10,
/// p2`): a run's summary reads like its net, and its JSON object keeps that order.
#[derive(Clone, Debug, PartialEq)]
pub struct InNetOrder<T>(Vec<(String, T)>);

impl<T> Default for InNetOrder<T> {
    fn default() -> Self {
        InNetOrder(Vec::new())
    }
}

impl<T> InNetOrder<T> {
    /// The value named `name`.
    pub fn get(&self, name: &str) -> Option<&T> {
        self.0.iter().find(|(n, _)| n == name).map(|(_, v)| v)
    }

    /// Names and values, in net order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &T)> {
        self.0.iter().map(|(n, v)| (n.as_str(), v))
    }

    /// The values, in net order.
    pub fn values(&self) -> impl Iterator<Item = &T> {
        self.0.iter().map(|(_, v)| v)
    }

    /// How many there are.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl<T> FromIterator<(String, T)> for InNetOrder<T> {
    fn from_iter<I: IntoIterator<Item = (String, T)>>(iter: I) -> Self {
        InNetOrder(iter.into_iter().collect())
    }
}

impl<T, Q: AsRef<str> + ?Sized> std::ops::Index<&Q> for InNetOrder<T> {
    type Output = T;

    /// Panics when there is no such name, like a map's index.
    fn index(&self, name: &Q) -> &T {
        let name = name.as_ref();
        self.get(name)
            .unwrap_or_else(|| panic!("no place or transition named `{name}`"))
    }
}

impl<T: Serialize> Serialize for InNetOrder<T> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}
