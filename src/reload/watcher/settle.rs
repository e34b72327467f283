//! Whether a burst's events say a file is completely saved, so that its batch need not
//! wait out the whole debounce.
//!
//! On Linux (inotify) a writer closing a file it wrote reports
//! `Access(Close(Write))`, and a rename reports `Modify(Name(From / To / Both))`; both
//! end a save. A write (`Modify(Data)`), a creation, or any event this cannot read
//! (rescans, other platforms' `Modify(Any)`) says a writer may still be at work.

use notify::event::{AccessKind, AccessMode, CreateKind, EventKind, ModifyKind, RenameMode};

/// What the events of the current burst say about one path.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Progress {
    /// Written to (or touched in a way this cannot read) with no close-after-write,
    /// rename or removal since: a writer may still be at work.
    open: bool,
    /// Created in this burst while not a known file, and still there: maybe an atomic
    /// save's temp file with a name [`is_editor_temp_file`](super::is_editor_temp_file)
    /// does not know, about to be renamed or removed (which settles it).
    fresh: bool,
}

impl Progress {
    /// State of a path the watcher cannot account for (a rescan after an overflow).
    pub(super) const UNKNOWN: Progress = Progress {
        open: true,
        fresh: false,
    };

    /// Whether the file is saved: closed after writing, renamed or created into place,
    /// removed, or only its metadata changed.
    pub(super) fn is_complete(&self) -> bool {
        !self.open && !self.fresh
    }

    /// Folds in one event on the path; `known`: whether the watcher knew it as a file
    /// before.
    pub(super) fn on(&mut self, kind: &EventKind, known: bool) {
        match kind {
            EventKind::Access(AccessKind::Close(AccessMode::Write)) => self.open = false,
            // Renamed into place (its content was complete before the rename), renamed
            // away or removed: nothing more to wait for under this name.
            EventKind::Modify(ModifyKind::Name(
                RenameMode::To | RenameMode::From | RenameMode::Both,
            ))
            | EventKind::Remove(_) => *self = Progress::default(),
            // chmod / utimes after a save: no writer at work.
            EventKind::Modify(ModifyKind::Metadata(_)) => {}
            EventKind::Create(CreateKind::Folder) => {}
            EventKind::Create(_) => {
                self.open = true;
                self.fresh |= !known;
            }
            _ => self.open = true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use notify::event::{DataChange, MetadataKind, RemoveKind};

    const CLOSE: EventKind = EventKind::Access(AccessKind::Close(AccessMode::Write));
    const WRITE: EventKind = EventKind::Modify(ModifyKind::Data(DataChange::Any));
    const CREATE: EventKind = EventKind::Create(CreateKind::File);

    fn after(events: &[EventKind], known: bool) -> Progress {
        let mut p = Progress::default();
        for e in events {
            p.on(e, known);
        }
        p
    }

    #[test]
    fn a_save_is_complete_when_closed_or_renamed_into_place() {
        assert!(after(&[WRITE, WRITE, CLOSE], true).is_complete());
        assert!(!after(&[WRITE], true).is_complete());
        assert!(!after(&[CLOSE, WRITE], true).is_complete());
        let to = EventKind::Modify(ModifyKind::Name(RenameMode::To));
        assert!(after(&[to], true).is_complete());
        assert!(
            after(&[to], false).is_complete(),
            "a new file renamed into place"
        );
        let attrib = EventKind::Modify(ModifyKind::Metadata(MetadataKind::Any));
        assert!(after(&[to, attrib], true).is_complete());
        assert!(after(&[attrib], true).is_complete());
        assert!(!after(&[WRITE, attrib], true).is_complete());
        // Other platforms' events this cannot read wait for the debounce.
        let any = EventKind::Modify(ModifyKind::Any);
        assert!(!after(&[any], true).is_complete());
        assert!(!after(&[EventKind::Any], true).is_complete());
        assert!(!Progress::UNKNOWN.is_complete());
    }

    #[test]
    fn a_new_file_waits_until_renamed_or_removed() {
        assert!(
            after(&[CREATE, WRITE, CLOSE], true).is_complete(),
            "recreated"
        );
        let new = after(&[CREATE, WRITE, CLOSE], false);
        assert!(!new.is_complete(), "maybe a temp file");
        let from = EventKind::Modify(ModifyKind::Name(RenameMode::From));
        assert!(after(&[CREATE, WRITE, CLOSE, from], false).is_complete());
        let removed = EventKind::Remove(RemoveKind::File);
        assert!(after(&[CREATE, CLOSE, removed], false).is_complete());
    }
}
