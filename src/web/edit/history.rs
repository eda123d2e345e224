//! The versions of the edited net: each edit adds one (dropping the ones that were undone),
//! undo and redo move between them. Versions are whole nets (shared, immutable): going back
//! is exact, whatever the edit was.

use std::sync::Arc;

use serde_json::{Value, json};

use super::{Edit, EditError, apply, positioned};
use crate::net::Net;

/// Versions kept besides the first (the oldest edits are forgotten past this; the net the
/// viewer was opened with is always kept).
pub(crate) const KEPT: usize = 200;

/// The net the viewer opened, every version since, and where the page is among them.
#[derive(Debug)]
pub(crate) struct History {
    /// `(net, the edit that made it)`; the first is the opened net (no edit).
    versions: Vec<(Arc<Net>, String)>,
    at: usize,
    /// Bumped by every edit, undo and redo: pages compare it with the one they drew.
    version: u64,
}

impl History {
    /// The history of `net`, not yet edited.
    pub(crate) fn new(net: Arc<Net>) -> History {
        History {
            versions: vec![(net, String::new())],
            at: 0,
            version: 0,
        }
    }

    /// The current version.
    pub(crate) fn net(&self) -> &Arc<Net> {
        &self.versions[self.at].0
    }

    /// Whether the current net differs from the opened one.
    pub(crate) fn edited(&self) -> bool {
        self.at != 0
    }

    /// The number the pages compare.
    pub(crate) fn version(&self) -> u64 {
        self.version
    }

    /// Applies `edit` to the current net, if `check` accepts the result (what it says of
    /// it comes back with the new net); the versions after it (undone ones) are dropped.
    pub(crate) fn apply<T>(
        &mut self,
        edit: &Edit,
        check: impl FnOnce(&Net) -> Result<T, EditError>,
    ) -> Result<(Arc<Net>, T), EditError> {
        let (net, label) = apply(&positioned(self.net()), edit)?;
        let checked = check(&net)?;
        self.versions.truncate(self.at + 1);
        self.versions.push((Arc::new(net), label));
        if self.versions.len() > KEPT + 1 {
            self.versions.remove(1);
        }
        self.at = self.versions.len() - 1;
        self.version += 1;
        Ok((self.net().clone(), checked))
    }

    /// Back to the version before the last edit, if `check` accepts it.
    pub(crate) fn undo<T>(
        &mut self,
        check: impl FnOnce(&Net) -> Result<T, EditError>,
    ) -> Result<(Arc<Net>, T), EditError> {
        if self.at == 0 {
            return Err(EditError::NothingToUndo);
        }
        self.go_to(self.at - 1, check)
    }

    /// On to the version the last undo left, if `check` accepts it.
    pub(crate) fn redo<T>(
        &mut self,
        check: impl FnOnce(&Net) -> Result<T, EditError>,
    ) -> Result<(Arc<Net>, T), EditError> {
        if self.at + 1 == self.versions.len() {
            return Err(EditError::NothingToRedo);
        }
        self.go_to(self.at + 1, check)
    }

    fn go_to<T>(
        &mut self,
        at: usize,
        check: impl FnOnce(&Net) -> Result<T, EditError>,
    ) -> Result<(Arc<Net>, T), EditError> {
        let checked = check(&self.versions[at].0)?;
        self.at = at;
        self.version += 1;
        Ok((self.net().clone(), checked))
    }

    /// `{version, edits, undo, redo}`: the labels of the edit an undo would take back and of
    /// the one a redo would do again (`null` when there is none).
    pub(crate) fn json(&self) -> Value {
        let undo = (self.at > 0).then(|| self.versions[self.at].1.clone());
        let redo = self.versions.get(self.at + 1).map(|v| v.1.clone());
        json!({
            "version": self.version,
            "edits": self.at,
            "undo": undo,
            "redo": redo,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::Servers;

    #[test]
    fn undo_and_redo_move_between_whole_versions() {
        let net = Arc::new(crate::net::cyc3(Servers::Single));
        let mut h = History::new(net.clone());
        let add: Edit = serde_json::from_value(
            json!({"op": "add_place", "name": "P4", "tokens": 1, "x": 0, "y": 0}),
        )
        .unwrap();
        let ok = |_: &Net| Ok(());
        h.apply(&add, ok).unwrap();
        assert_eq!(h.net().place_count(), 4);
        assert_eq!(h.json()["undo"], "add place P4");
        h.undo(ok).unwrap();
        assert!(h.net().diff(&net).is_empty() && !h.edited());
        assert_eq!(h.json()["redo"], "add place P4");
        assert_eq!(h.undo(ok).unwrap_err(), EditError::NothingToUndo);
        h.redo(ok).unwrap();
        assert_eq!(h.net().place_count(), 4);
        assert_eq!(h.redo(ok).unwrap_err(), EditError::NothingToRedo);
        // A refused edit leaves everything as it was.
        let before = h.json();
        assert!(h.apply(&add, ok).is_err());
        assert_eq!(h.json(), before);
        assert_eq!(h.version(), 3);
        // So does an edit, an undo or a redo the check refuses (the plan it would break).
        let no = |_: &Net| Err::<(), _>(EditError::Nothing);
        let other: Edit =
            serde_json::from_value(json!({"op": "add_place", "name": "P5", "x": 0, "y": 0}))
                .unwrap();
        assert_eq!(h.apply(&other, no).unwrap_err(), EditError::Nothing);
        assert_eq!(h.undo(no).unwrap_err(), EditError::Nothing);
        assert_eq!(h.json(), before);
        h.undo(ok).unwrap();
        assert_eq!(h.redo(no).unwrap_err(), EditError::Nothing);
        assert!(!h.edited());
    }
}
