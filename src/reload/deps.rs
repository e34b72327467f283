//! Which things (pipelines, materials, graphs: any string key) depend on which files.

use super::watcher::normalize_path;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A many-to-many index between files and the things built from them.
///
/// Keys are free-form strings (e.g. `"pipeline:forward_plus/shade"`). A dependent's file set
/// should include every file it pulls in, includes too: register the full, resolved set with
/// [`set_dependencies`](Self::set_dependencies) each time the dependent is (re)built, since its
/// includes may have changed.
///
/// Paths are normalised with [`normalize_path`] on the way in and on lookup (absolute,
/// symlinks resolved where the file exists), so relative registrations match the absolute paths
/// that [`FileWatcher`](super::FileWatcher) reports.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct DependencyIndex {
    by_path: BTreeMap<PathBuf, BTreeSet<String>>,
    by_dependent: BTreeMap<String, BTreeSet<PathBuf>>,
}

impl DependencyIndex {
    /// An empty index.
    pub fn new() -> Self {
        Self::default()
    }

    /// Record that `dependent` uses `path` (in addition to what it already uses).
    pub fn add(&mut self, path: impl AsRef<Path>, dependent: impl Into<String>) {
        let path = normalize_path(path.as_ref());
        let dependent = dependent.into();
        self.by_path
            .entry(path.clone())
            .or_default()
            .insert(dependent.clone());
        self.by_dependent.entry(dependent).or_default().insert(path);
    }

    /// Replace everything `dependent` uses with `paths` (an empty set removes it).
    pub fn set_dependencies<P: AsRef<Path>>(
        &mut self,
        dependent: impl Into<String>,
        paths: impl IntoIterator<Item = P>,
    ) {
        let dependent = dependent.into();
        self.remove_dependent(&dependent);
        for p in paths {
            self.add(p, dependent.clone());
        }
    }

    /// Forget `dependent`; returns whether it was known.
    pub fn remove_dependent(&mut self, dependent: &str) -> bool {
        let Some(paths) = self.by_dependent.remove(dependent) else {
            return false;
        };
        for p in paths {
            if let Some(set) = self.by_path.get_mut(&p) {
                set.remove(dependent);
                if set.is_empty() {
                    self.by_path.remove(&p);
                }
            }
        }
        true
    }

    /// The things that use `path`.
    pub fn dependents_of(&self, path: impl AsRef<Path>) -> BTreeSet<String> {
        self.by_path
            .get(&normalize_path(path.as_ref()))
            .cloned()
            .unwrap_or_default()
    }

    /// The (normalised) files `dependent` uses.
    pub fn dependencies_of(&self, dependent: &str) -> BTreeSet<PathBuf> {
        self.by_dependent
            .get(dependent)
            .cloned()
            .unwrap_or_default()
    }

    /// Everything that must be rebuilt when `changed` files changed.
    pub fn affected<P: AsRef<Path>>(
        &self,
        changed: impl IntoIterator<Item = P>,
    ) -> BTreeSet<String> {
        let mut out = BTreeSet::new();
        for p in changed {
            if let Some(set) = self.by_path.get(&normalize_path(p.as_ref())) {
                out.extend(set.iter().cloned());
            }
        }
        out
    }

    /// Every file some dependent uses (what to watch).
    pub fn paths(&self) -> impl Iterator<Item = &Path> {
        self.by_path.keys().map(PathBuf::as_path)
    }

    /// Every registered dependent.
    pub fn dependents(&self) -> impl Iterator<Item = &str> {
        self.by_dependent.keys().map(String::as_str)
    }

    /// Whether nothing is registered.
    pub fn is_empty(&self) -> bool {
        self.by_dependent.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(items: &[&str]) -> BTreeSet<String> {
        items.iter().map(|s| s.to_string()).collect()
    }

    fn index() -> DependencyIndex {
        let mut d = DependencyIndex::new();
        d.set_dependencies(
            "pipeline:forward",
            [
                "shaders/forward.wgsl",
                "shaders/lights.wgsl",
                "shaders/brdf.wgsl",
            ],
        );
        d.set_dependencies(
            "pipeline:cull",
            ["shaders/cull.wgsl", "shaders/lights.wgsl"],
        );
        d.add("materials/gold.ron", "material:gold");
        d
    }

    #[test]
    fn affected_maps_changes_to_dependents() {
        let d = index();
        assert_eq!(
            d.affected(["shaders/brdf.wgsl"]),
            set(&["pipeline:forward"])
        );
        assert_eq!(
            d.affected(["shaders/lights.wgsl"]),
            set(&["pipeline:cull", "pipeline:forward"])
        );
        assert_eq!(
            d.affected(["shaders/cull.wgsl", "materials/gold.ron", "README.md"]),
            set(&["material:gold", "pipeline:cull"])
        );
        assert!(d.affected(Vec::<PathBuf>::new()).is_empty());
        assert!(d.affected(["shaders/unknown.wgsl"]).is_empty());
    }

    #[test]
    fn relative_and_absolute_paths_match() {
        let d = index();
        let abs = std::env::current_dir()
            .unwrap()
            .join("shaders/./sub/../brdf.wgsl");
        assert_eq!(d.affected([abs]), set(&["pipeline:forward"]));
    }

    #[test]
    fn set_dependencies_replaces_includes() {
        let mut d = index();
        // forward no longer includes brdf.wgsl but now includes shadow.wgsl.
        d.set_dependencies(
            "pipeline:forward",
            [
                "shaders/forward.wgsl",
                "shaders/lights.wgsl",
                "shaders/shadow.wgsl",
            ],
        );
        assert!(d.affected(["shaders/brdf.wgsl"]).is_empty());
        assert_eq!(
            d.affected(["shaders/shadow.wgsl"]),
            set(&["pipeline:forward"])
        );
        assert_eq!(d.dependencies_of("pipeline:forward").len(), 3);
        assert!(!d.paths().any(|p| p.ends_with("brdf.wgsl")));
    }

    #[test]
    fn remove_dependent_cleans_up() {
        let mut d = index();
        assert!(d.remove_dependent("pipeline:cull"));
        assert!(!d.remove_dependent("pipeline:cull"));
        assert!(d.affected(["shaders/cull.wgsl"]).is_empty());
        assert_eq!(
            d.dependents_of("shaders/lights.wgsl"),
            set(&["pipeline:forward"])
        );
        d.set_dependencies("pipeline:forward", Vec::<PathBuf>::new());
        d.remove_dependent("material:gold");
        assert!(d.is_empty());
        assert_eq!(d.paths().count(), 0);
    }
}
