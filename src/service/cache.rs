//! The metamodels read back from the store, kept loaded for the sampling requests that follow,
//! with a bound on how many.

use super::AppState;
use super::supervision::{blocking, through_faults};
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::study::Study;
use crate::surrogate::Metamodel;
use lru::LruCache;
use std::num::NonZeroUsize;
use std::sync::Arc;

/// A stored metamodel read back, with the study it rebuilds.
pub type Loaded = Arc<(Metamodel, Study)>;

/// Loaded metamodels by id, the least recently used dropped first. A metamodel holds its study's
/// modes and spectral table (a few MB at full size), so the bound is what bounds this memory.
///
/// A load reads the store, then parses off the runtime; a delete in between must not be undone by
/// the load's insertion. Every delete advances `generation`; a load remembers the generation it
/// started in and caches its result only if no delete happened since.
pub struct LoadedMetamodels<V = Loaded> {
    /// The cache proper.
    entries: LruCache<String, V>,
    /// Deletes so far on this replica.
    generation: u64,
}

impl<V: Clone> LoadedMetamodels<V> {
    pub fn new(capacity: usize) -> Self {
        let capacity = NonZeroUsize::new(capacity.max(1)).expect("at least one");
        LoadedMetamodels { entries: LruCache::new(capacity), generation: 0 }
    }

    /// The loaded metamodel, marked as just used.
    pub fn get(&mut self, id: &str) -> Option<V> {
        self.entries.get(id).cloned()
    }

    /// What a load must hand back to [`LoadedMetamodels::insert`].
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Keeps a loaded metamodel unless a delete happened since `generation` was read.
    pub fn insert(&mut self, id: &str, loaded: V, generation: u64) {
        if generation == self.generation {
            self.entries.put(id.to_string(), loaded);
        }
    }

    /// Forgets a metamodel that was deleted (or found missing in the store).
    pub fn remove(&mut self, id: &str) {
        self.entries.pop(id);
        self.generation += 1;
    }
}

/// A stored metamodel's body read back, with the study it rebuilds (blocking).
pub(super) fn rebuilt(body: &str) -> Result<(Metamodel, Study)> {
    let metamodel = Metamodel::from_json(body)?;
    let study = metamodel.study()?;
    Ok((metamodel, study))
}

/// A stored metamodel and its study for a job or a task, from this replica's cache or read and
/// cached; an error naming `metamodel_id` when it was deleted.
pub(super) async fn stored_metamodel(state: &AppState, id: &str, supervision: &dyn Observer) -> Result<Loaded> {
    let (cached, generation) = {
        let mut loaded = state.loaded.lock().expect("cache lock");
        (loaded.get(id), loaded.generation())
    };
    if let Some(found) = cached {
        return Ok(found);
    }
    let body = through_faults(supervision, "reading a metamodel", || state.store.metamodel_body(id))
        .await?
        .ok_or_else(|| Error::invalid("metamodel_id", "the metamodel was deleted"))?;
    let loaded = Arc::new(blocking(move || rebuilt(&body)).await?);
    state.loaded.lock().expect("cache lock").insert(id, loaded.clone(), generation);
    Ok(loaded)
}

#[cfg(test)]
mod tests {
    use super::LoadedMetamodels;

    #[test]
    fn the_least_recently_used_goes_first() {
        let mut cache = LoadedMetamodels::new(2);
        let g = cache.generation();
        cache.insert("a", 1, g);
        cache.insert("b", 2, g);
        assert_eq!(cache.get("a"), Some(1));
        cache.insert("c", 3, g);
        assert_eq!((cache.get("a"), cache.get("b"), cache.get("c")), (Some(1), None, Some(3)));
    }

    /// A load that started before a delete finishes after it: its result must not come back.
    #[test]
    fn a_delete_during_a_load_is_not_undone() {
        let mut cache = LoadedMetamodels::new(4);
        let started = cache.generation();
        cache.remove("m");
        cache.insert("m", 1, started);
        assert_eq!(cache.get("m"), None);
        let after = cache.generation();
        cache.insert("m", 1, after);
        assert_eq!(cache.get("m"), Some(1));
    }
}
