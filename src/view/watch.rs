//! The scene's files (the scene file, its glTF files and images: `Scene::inputs`), watched by
//! polling their modification times and sizes (editors that save by renaming a new file over the
//! old one are seen too; no platform watcher to install).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

type Stamp = Option<(SystemTime, u64)>;

pub struct Watch {
    files: Vec<(PathBuf, Stamp)>,
    last_poll: Instant,
}

/// How often the files are looked at.
const POLL: Duration = Duration::from_millis(25);

fn stamp(path: &Path) -> Stamp {
    let m = std::fs::metadata(path).ok()?;
    Some((m.modified().ok()?, m.len()))
}

impl Watch {
    pub fn new(files: &[PathBuf]) -> Watch {
        let mut w = Watch {
            files: Vec::new(),
            last_poll: Instant::now(),
        };
        w.set_files(files);
        w
    }

    /// Watches `files` from now on (after a reload: the scene may name others); the files
    /// watched before keep what was seen of them.
    pub fn set_files(&mut self, files: &[PathBuf]) {
        let old = std::mem::take(&mut self.files);
        self.files = files
            .iter()
            .map(|f| {
                let seen = old
                    .iter()
                    .find(|(p, _)| p == f)
                    .map_or_else(|| stamp(f), |o| o.1);
                (f.clone(), seen)
            })
            .collect();
    }

    /// When a file changed since the last call that said so: its modification time.
    pub fn changed(&mut self) -> Option<SystemTime> {
        if self.last_poll.elapsed() < POLL {
            return None;
        }
        self.last_poll = Instant::now();
        let mut latest = None;
        for (path, seen) in &mut self.files {
            let now = stamp(path);
            // A file gone for a moment (a save by rename) is not an edit.
            if now.is_none() || now == *seen {
                continue;
            }
            *seen = now;
            latest = latest.max(now.map(|s| s.0));
        }
        latest
    }
}
