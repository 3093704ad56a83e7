//! The acceleration structure of a [`RaycastingScene`](super::RaycastingScene), built on the
//! first query after a change (and the border of the counting rule, on the first counting
//! query: see [`border`]). A large build (a million triangles: about a second) runs on a
//! thread of its own while the query waits for it watching its cancel flag, so that Ctrl-C
//! is answered at once; the build, left to finish, then serves the next query. A small one
//! runs on the caller's thread.

use std::ops::Range;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Duration;

use std::collections::HashMap;

use glam::Vec3;

use super::run::QueryOptions;
use super::RaycastError;
use crate::accel::placed::Placement;
use crate::accel::wide::levels::{Borders, WideLevels};
use crate::accel::wide::WideBvh;
use crate::accel::AlphaTests;
use crate::geometry::Geometry;

/// Triangles below this many are built on the calling thread (a few milliseconds).
const ON_THREAD: usize = 1 << 15;

/// How often a waiting query looks at its cancel flag.
const POLL: Duration = Duration::from_millis(5);

/// A mesh's tree, and its vertices with the largest magnitude of their coordinates (to check
/// where a placement puts them).
#[derive(Clone, Debug)]
pub(crate) struct MeshTree {
    pub tree: Arc<WideBvh>,
    pub positions: Arc<[Vec3]>,
    /// The largest `|coordinate|` of any of `positions`, used by a triangle or not.
    pub reach: f32,
}

impl MeshTree {
    /// The mesh tree `tree` over `positions`.
    pub fn new(tree: Arc<WideBvh>, positions: Arc<[Vec3]>) -> MeshTree {
        let reach = (positions.iter()).fold(0.0f32, |r, p| r.max(p.abs().max_element()));
        MeshTree {
            tree,
            positions,
            reach,
        }
    }
}

/// The triangles of a scene and each one's index within its own geometry, and the meshes
/// placed, shared with a build that outlives a cancelled query.
#[derive(Clone, Debug, Default)]
pub(crate) struct Triangles {
    /// Every triangle of the own geometries; `Triangle::object` is its geometry id.
    pub geometry: Geometry,
    /// For each triangle of `geometry`, its index within its own geometry.
    pub local_ids: Vec<u32>,
    /// For each geometry id, where its vertices and triangles lie in `geometry`.
    pub spans: Vec<Span>,
    /// The alpha test of each triangle of `geometry` (by index), when some may be cut out
    /// (a scene made from a world with cut-out materials); `None` otherwise.
    pub alpha: Option<Arc<AlphaTests>>,
    /// The trees of the meshes placements place, each built once.
    pub meshes: Vec<MeshTree>,
    /// For each own geometry placed, its mesh tree and that mesh's alpha tests.
    pub mesh_of: HashMap<u32, (u32, Option<Arc<AlphaTests>>)>,
    /// For each placement's geometry id, its index in `placements`.
    pub placed: HashMap<u32, u32>,
    /// Every placement, in the order added.
    pub placements: Vec<Placement>,
    /// For each placement of a placement, the geometry id of the placement it places.
    pub placed_on: HashMap<u32, u32>,
}

impl Triangles {
    /// Triangles that rays see: the own ones, and each placement's mesh's.
    pub fn seen(&self) -> usize {
        let placed = self.placements.iter();
        self.geometry.len()
            + placed
                .map(|p| self.meshes[p.mesh as usize].tree.tris().len())
                .sum::<usize>()
    }
}

/// Where one geometry lies in [`Triangles::geometry`]: its vertices are `vertices` (each
/// geometry's are contiguous), and its triangles are those of `triangles` whose `object` is
/// its id.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Span {
    /// Its vertices.
    pub vertices: Range<u32>,
    /// A range of triangles that holds all of its own.
    pub triangles: Range<u32>,
}

/// Where a build stands.
#[derive(Debug)]
enum State {
    Building,
    Built(Arc<WideLevels>),
    /// Built, and placements moved since: the top level is built again on the next query.
    Moved(Arc<WideLevels>),
    /// The build's thread ended without a result (it panicked).
    Lost,
}

/// One build and the queries waiting for it.
#[derive(Debug)]
struct Build {
    state: Mutex<State>,
    done: Condvar,
}

impl Build {
    fn state(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn finish(&self, state: State) {
        *self.state() = state;
        self.done.notify_all();
    }

    /// The built structure, waiting for it while `options` is not cancelled; moved
    /// placements are placed as `triangles` has them now.
    fn wait(
        &self,
        triangles: &Triangles,
        options: &QueryOptions,
    ) -> Result<Arc<WideLevels>, RaycastError> {
        let mut state = self.state();
        loop {
            match &*state {
                State::Built(accel) => return Ok(accel.clone()),
                State::Moved(accel) => {
                    let placements = triangles.placements.clone();
                    let moved = Arc::new(accel.replaced(placements, None));
                    *state = State::Built(moved.clone());
                    return Ok(moved);
                }
                State::Lost => {
                    return Err(RaycastError::Threads(
                        "the acceleration structure's build failed".into(),
                    ))
                }
                State::Building if options.cancelled() => return Err(RaycastError::Cancelled),
                State::Building => {
                    state = match self.done.wait_timeout(state, POLL) {
                        Ok((s, _)) => s,
                        Err(e) => e.into_inner().0,
                    };
                }
            }
        }
    }
}

/// Marks a build lost when its thread ends without finishing it.
struct Finish(Arc<Build>);

impl Drop for Finish {
    fn drop(&mut self) {
        let mut state = self.0.state();
        if matches!(*state, State::Building) {
            *state = State::Lost;
            self.0.done.notify_all();
        }
    }
}

/// The scene's structure: none yet, or the build of the current triangles.
#[derive(Debug, Default)]
pub(crate) struct LazyAccel {
    build: Mutex<Option<Arc<Build>>>,
}

impl LazyAccel {
    /// Takes `levels` as the structure built.
    pub fn set(&self, levels: Arc<WideLevels>) {
        let build = Build {
            state: Mutex::new(State::Built(levels)),
            done: Condvar::new(),
        };
        *self.build.lock().unwrap_or_else(|e| e.into_inner()) = Some(Arc::new(build));
    }

    /// Marks placements moved: the structure built keeps its trees and builds its top level
    /// again on the next query. Without one built (none, or still building), forgets it.
    pub fn moved(&mut self) {
        let slot = self.build.get_mut().unwrap_or_else(|e| e.into_inner());
        let built = slot.as_ref().and_then(|b| match &*b.state() {
            State::Built(levels) | State::Moved(levels) => Some(levels.clone()),
            _ => None,
        });
        *slot = built.map(|levels| {
            Arc::new(Build {
                state: Mutex::new(State::Moved(levels)),
                done: Condvar::new(),
            })
        });
    }

    /// Forgets the structure: the triangles changed. A build still running finishes for
    /// nobody.
    pub fn reset(&mut self) {
        *self.build.get_mut().unwrap_or_else(|e| e.into_inner()) = None;
    }

    /// The structure over `triangles`, built on `pool` by the first caller; `Err(Cancelled)`
    /// as soon as `options` is cancelled while it is being built.
    pub fn get(
        &self,
        triangles: &Arc<Triangles>,
        pool: &Arc<rayon::ThreadPool>,
        options: &QueryOptions,
    ) -> Result<Arc<WideLevels>, RaycastError> {
        let build = {
            let mut slot = self.build.lock().unwrap_or_else(|e| e.into_inner());
            match &*slot {
                Some(build) => build.clone(),
                None => {
                    let build = Arc::new(Build {
                        state: Mutex::new(State::Building),
                        done: Condvar::new(),
                    });
                    *slot = Some(build.clone());
                    start(&build, triangles, pool);
                    build
                }
            }
        };
        build.wait(triangles, options)
    }
}

/// Builds over `triangles` into `build`: on a thread of its own when they are many and the
/// thread starts, else here.
fn start(build: &Arc<Build>, triangles: &Arc<Triangles>, pool: &Arc<rayon::ThreadPool>) {
    let work = {
        let (build, triangles, pool) = (build.clone(), triangles.clone(), pool.clone());
        move || {
            let finish = Finish(build);
            let t = &triangles;
            let own = Arc::new(WideBvh::build(&t.geometry, &t.local_ids, Some(&pool)));
            let meshes = t.meshes.iter().map(|m| m.tree.clone()).collect();
            let placements = t.placements.clone();
            let levels = WideLevels::new(own, t.alpha.clone(), meshes, placements, Some(&pool));
            finish.0.finish(State::Built(Arc::new(levels)));
        }
    };
    if triangles.geometry.len() < ON_THREAD {
        return work();
    }
    // A thread that cannot start leaves the build to this one.
    let spawned = std::thread::Builder::new()
        .name("penumbra-raycast-build".into())
        .spawn(work.clone());
    if spawned.is_err() {
        work();
    }
}

/// [`WideLevels::borders`] for a counting query: made on a thread of its own for a large
/// scene (a sort of every edge: a few tenths of a second for a million triangles) while the
/// query waits watching its cancel flag; a cancelled query returns at once, and the work, left
/// to finish, serves the next one.
pub(crate) fn borders<'a>(
    accel: &'a Arc<WideLevels>,
    pool: &Arc<rayon::ThreadPool>,
    options: &QueryOptions,
) -> Result<Borders<'a>, RaycastError> {
    if let Some(borders) = accel.made_borders() {
        return Ok(borders);
    }
    if accel.unique_triangles() < ON_THREAD {
        return Ok(accel.borders(pool));
    }
    // Several waiting queries may start a thread each: one makes it, the others wait for it.
    let (a, p) = (accel.clone(), pool.clone());
    let spawned = std::thread::Builder::new()
        .name("penumbra-raycast-border".into())
        .spawn(move || {
            a.borders(&p);
        });
    if spawned.is_err() {
        return Ok(accel.borders(pool));
    }
    loop {
        if let Some(borders) = accel.made_borders() {
            return Ok(borders);
        }
        if options.cancelled() {
            return Err(RaycastError::Cancelled);
        }
        std::thread::sleep(POLL);
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::time::Instant;

    use super::super::{QueryOptions, RaycastError, RaycastingScene};
    use crate::sampling::Rng;

    /// A soup of `n` small random triangles in the unit cube.
    fn soup(n: usize) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let mut rng = Rng::new(5, &[]);
        let v: Vec<[f32; 3]> = (0..3 * n).map(|_| [0; 3].map(|_| rng.uniform())).collect();
        let t = (0..n as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        (v, t)
    }

    /// Counts `rays` with a cancel set `delay_ms` after the query starts: the result, and how
    /// long after the cancel the query answered.
    fn count_cancelled_after(
        scene: &RaycastingScene,
        rays: &[[f32; 6]],
        delay_ms: u64,
    ) -> (Result<Vec<i32>, RaycastError>, std::time::Duration) {
        let cancel = AtomicBool::new(false);
        let options = QueryOptions {
            threads: 2,
            cancel: Some(&cancel),
        };
        let (result, sent, answered) = std::thread::scope(|s| {
            let sender = s.spawn(|| {
                std::thread::sleep(std::time::Duration::from_millis(delay_ms));
                cancel.store(true, Ordering::Relaxed);
                Instant::now()
            });
            let result = scene.count_intersections(rays, &options);
            let answered = Instant::now();
            (result, sender.join().unwrap(), answered)
        });
        (result, answered.saturating_duration_since(sent))
    }

    #[test]
    fn a_query_cancelled_during_the_build_or_the_border_returns_at_once() {
        // Half a million triangles: a build of a second or more here.
        let (v, t) = soup(1 << 19);
        let mut scene = RaycastingScene::new();
        scene.add_triangles(&v, &t).unwrap();
        let rays = [[0.5, 0.5, -1.0, 0.0, 0.0, 1.0]];
        let (result, latency) = count_cancelled_after(&scene, &rays, 30);
        assert_eq!(result, Err(RaycastError::Cancelled));
        assert!(latency.as_secs_f64() < 0.1, "{latency:?} after the cancel");
        // The build went on, and serves the next query; so does the border of the counting
        // rule, made on the first counting query and cancelled the same way.
        scene.commit(2).unwrap();
        let (result, latency) = count_cancelled_after(&scene, &rays, 10);
        assert_eq!(result, Err(RaycastError::Cancelled));
        assert!(latency.as_secs_f64() < 0.1, "{latency:?} after the cancel");
        // A change starts another build.
        let plain = QueryOptions::default();
        let started = Instant::now();
        let first = scene.count_intersections(&rays, &plain).unwrap();
        eprintln!("the rest of the build: {:?}", started.elapsed());
        assert!(first[0] > 0);
        scene.add_triangles(&v[..3], &[[0, 1, 2]]).unwrap();
        let again = scene.count_intersections(&rays, &plain).unwrap();
        assert!(again[0] >= first[0]);
    }
}
