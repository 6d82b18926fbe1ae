//! The metamodels read back from the store, kept loaded for the sampling requests and jobs that
//! follow, with a bound on how many. Routes, jobs and tasks all load a stored metamodel through
//! [`MetamodelCache::for_request`] or [`MetamodelCache::for_work`]; the cache's lock is taken
//! nowhere else.

use super::error::ApiError;
use super::store::Store;
use super::supervision::{blocking, through_faults};
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::study::Study;
use crate::surrogate::Metamodel;
use lru::LruCache;
use std::num::NonZeroUsize;
use std::sync::{Arc, Mutex};

/// A stored metamodel read back, with the study it rebuilds (modes, spectral table).
pub struct StoredMetamodel {
    /// The fitted metamodel as stored.
    pub metamodel: Metamodel,
    /// The study the metamodel was calibrated on, rebuilt from the metamodel's own description.
    pub study: Study,
}

impl StoredMetamodel {
    /// A stored metamodel's body read back, with the study it rebuilds (blocking: parsing and the
    /// modal analysis take a few milliseconds at full size).
    pub fn rebuilt(body: &str) -> Result<StoredMetamodel> {
        let metamodel = Metamodel::from_json(body)?;
        let study = metamodel.study()?;
        Ok(StoredMetamodel { metamodel, study })
    }
}

/// A loaded metamodel as the cache hands it out, shared by the requests and jobs that use it.
pub type Loaded = Arc<StoredMetamodel>;

/// The loaded metamodels of this replica, by id; a delete anywhere forgets the one it names.
pub struct MetamodelCache {
    loaded: Mutex<LoadedMetamodels<Loaded>>,
}

impl MetamodelCache {
    /// A cache of at most `capacity` metamodels (at least one).
    pub fn new(capacity: usize) -> Self {
        MetamodelCache { loaded: Mutex::new(LoadedMetamodels::new(capacity)) }
    }

    /// The stored metamodel `id` for a request being answered: a cached one is still looked up in
    /// the store (one indexed read), so that a delete through another replica is seen at once; 404
    /// when there is none, 503 when the database does not answer.
    pub async fn for_request(&self, store: &Store, id: &str) -> std::result::Result<Loaded, ApiError> {
        let (cached, generation) = self.cached(id);
        if let Some(found) = cached {
            if store.metamodel_exists(id).await? {
                return Ok(found);
            }
            self.forget(id);
            return Err(ApiError::not_found("metamodel", id));
        }
        let body = store.metamodel_body(id).await?.ok_or_else(|| ApiError::not_found("metamodel", id))?;
        Ok(self.keep(id, body, generation).await?)
    }

    /// The stored metamodel `id` for a job or a task under `supervision`: a cached one as it is,
    /// otherwise read through transient database faults until the store answers or the work is
    /// cancelled; an error naming `metamodel_id` when it was deleted.
    pub async fn for_work(&self, store: &Store, id: &str, supervision: &dyn Observer) -> Result<Loaded> {
        let (cached, generation) = self.cached(id);
        if let Some(found) = cached {
            return Ok(found);
        }
        let body = through_faults(supervision, "reading a metamodel", || store.metamodel_body(id))
            .await?
            .ok_or_else(|| Error::invalid("metamodel_id", "the metamodel was deleted"))?;
        self.keep(id, body, generation).await
    }

    /// Forgets a metamodel that was deleted; a load that started before will not put it back.
    pub fn forget(&self, id: &str) {
        self.lock().remove(id);
    }

    /// The cached metamodel, if any, and the generation a load of it must hand back.
    fn cached(&self, id: &str) -> (Option<Loaded>, u64) {
        let mut loaded = self.lock();
        (loaded.get(id), loaded.generation())
    }

    /// Rebuilds a stored body off the runtime and keeps it, unless a delete happened meanwhile.
    async fn keep(&self, id: &str, body: String, generation: u64) -> Result<Loaded> {
        let loaded = Arc::new(blocking(move || StoredMetamodel::rebuilt(&body)).await?);
        self.lock().insert(id, loaded.clone(), generation);
        Ok(loaded)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, LoadedMetamodels<Loaded>> {
        self.loaded.lock().expect("the metamodel cache's lock")
    }
}

/// Loaded metamodels by id, the least recently used dropped first. A metamodel holds its study's
/// modes and spectral table (a few MB at full size), so the bound is what bounds this memory.
///
/// A load reads the store, then parses off the runtime; a delete in between must not be undone by
/// the load's insertion. Every delete advances `generation`; a load remembers the generation it
/// started in and caches its result only if no delete happened since.
struct LoadedMetamodels<V> {
    /// The cache proper.
    entries: LruCache<String, V>,
    /// Deletes so far on this replica.
    generation: u64,
}

impl<V: Clone> LoadedMetamodels<V> {
    fn new(capacity: usize) -> Self {
        let capacity = NonZeroUsize::new(capacity.max(1)).expect("at least one");
        LoadedMetamodels { entries: LruCache::new(capacity), generation: 0 }
    }

    /// The loaded metamodel, marked as just used.
    fn get(&mut self, id: &str) -> Option<V> {
        self.entries.get(id).cloned()
    }

    /// What a load must hand back to [`LoadedMetamodels::insert`].
    fn generation(&self) -> u64 {
        self.generation
    }

    /// Keeps a loaded metamodel unless a delete happened since `generation` was read.
    fn insert(&mut self, id: &str, loaded: V, generation: u64) {
        if generation == self.generation {
            self.entries.put(id.to_string(), loaded);
        }
    }

    /// Forgets a metamodel that was deleted (or found missing in the store).
    fn remove(&mut self, id: &str) {
        self.entries.pop(id);
        self.generation += 1;
    }
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
