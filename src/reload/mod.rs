//! Hot reload plumbing: a debounced file watcher that survives every way editors save
//! ([`watcher`]) and an index from files to what depends on them ([`deps`]), so a batch of
//! changed files maps to exactly the pipelines / materials / graphs to rebuild.
//!
//! ```no_run
//! use lightgraph::reload::{DependencyIndex, FileWatcher, WatchConfig};
//! use std::time::Duration;
//!
//! let mut watcher = FileWatcher::new(WatchConfig::default()).unwrap();
//! watcher.watch("shaders").unwrap();
//! let mut deps = DependencyIndex::new();
//! deps.set_dependencies("pipeline:forward", ["shaders/forward.wgsl", "shaders/lights.wgsl"]);
//! if let Some(batch) = watcher.wait_for_change(Duration::from_millis(16)) {
//!     for pipeline in deps.affected(batch.paths()) {
//!         println!("rebuild {pipeline}");
//!     }
//! }
//! ```

pub mod deps;
pub mod session;
pub mod watcher;

pub use deps::DependencyIndex;
pub use session::{Reload, ReloadSession, ReloadTimings, SceneSource};
pub use watcher::{
    is_editor_temp_file, normalize_path, ChangeBatch, ChangeKind, FileWatcher, WatchConfig,
    WatchError,
};
