//! The scene file, watched by polling its modification time and size (editors that save by
//! renaming a new file over the old one are seen too; no platform watcher to install).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

pub struct Watch {
    path: PathBuf,
    seen: Option<(SystemTime, u64)>,
    last_poll: Instant,
}

/// How often the file is looked at.
const POLL: Duration = Duration::from_millis(25);

fn stamp(path: &Path) -> Option<(SystemTime, u64)> {
    let m = std::fs::metadata(path).ok()?;
    Some((m.modified().ok()?, m.len()))
}

impl Watch {
    pub fn new(path: &Path) -> Watch {
        Watch {
            path: path.to_path_buf(),
            seen: stamp(path),
            last_poll: Instant::now(),
        }
    }

    /// The file's modification time when it changed since the last call that said so.
    pub fn changed(&mut self) -> Option<SystemTime> {
        if self.last_poll.elapsed() < POLL {
            return None;
        }
        self.last_poll = Instant::now();
        let now = stamp(&self.path);
        if now.is_none() || now == self.seen {
            // A file gone for a moment (a save by rename) is not an edit.
            return None;
        }
        self.seen = now;
        now.map(|s| s.0)
    }
}
