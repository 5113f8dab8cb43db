//! What a refinement's step hook holds against what the memory estimate adds for it, measured
//! as heap: this binary's allocator counts every byte, and it holds this one test, so nothing
//! else allocates into the count while it runs.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

use eddy::pipeline::{Footprint, Pipeline};

/// The heap this process holds, bytes: every allocation counted as it is made and freed.
static HELD: AtomicUsize = AtomicUsize::new(0);

/// The system allocator, counting into [`HELD`].
struct Counting;

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            HELD.fetch_add(layout.size(), Relaxed);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            HELD.fetch_add(layout.size(), Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        HELD.fetch_sub(layout.size(), Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            HELD.fetch_add(new_size, Relaxed);
            HELD.fetch_sub(layout.size(), Relaxed);
        }
        p
    }
}

#[global_allocator]
static COUNTING: Counting = Counting;

/// The hooks' per-particle state (Rankine's omega^(n-1), VRSPH's zeta and stretching, MCVSPH's
/// samples and vorticity, micropolar's angular velocity) and the buffers they keep are made in
/// their first steps, after the set-up, and are no part of the solver's `memory_bytes`. For
/// the hydrostatic tank (at rest, so every run has the same neighbourhoods) without a
/// refinement and under each registered method, three steps in:
///
/// - what the refinement holds (the heap with the method less the heap without: the hook's
///   arrays and the operators' volumes the solver keeps for it) is at most what the estimate
///   adds for it (the estimate with the method less the one without);
/// - the heap the whole pipeline holds, the hook's included, is at most the estimate.
#[test]
fn the_memory_estimate_bounds_what_a_refinement_holds() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/hydrostatic_tank.toml");
    // (estimate, heap held) of the tank under `method`, three steps in.
    let measure = |method: &str| {
        let overrides = [
            format!("refinement.method={method:?}"),
            "output.metrics=[]".into(),
        ];
        let scene = eddy::scene::load(&path, &overrides).expect("the scene");
        let spec = eddy::scene::build::run_spec(&scene).expect("the run");
        let estimate = Footprint::of(&spec).bytes;
        let before = HELD.load(Relaxed);
        let mut p = Pipeline::build(&scene).expect("builds");
        for _ in 0..3 {
            p.step(None, None).expect("steps");
        }
        let held = HELD.load(Relaxed) as f64 - before as f64;
        let n = p.sim.sph.as_ref().expect("a fluid").fluid.len() as f64;
        (estimate, held, n)
    };
    // The first build starts the thread pool and fills the lazy tables; it is not counted.
    measure("none");
    let (estimate_none, held_none, _) = measure("none");
    let methods = eddy::refine::registry::methods();
    assert!(methods.len() >= 5, "the built-in methods");
    for method in methods.iter().map(|m| m.name) {
        let (estimate, held, n) = measure(method);
        let added = held - held_none;
        let allowed = estimate - estimate_none;
        eprintln!(
            "{method}: {n} particles, {held:.0} B held, {estimate:.0} B estimated; the \
             refinement adds {added:.0} B ({:.2} B per particle), the estimate {allowed:.0} B",
            added / n
        );
        assert!(
            added <= allowed,
            "{method}: its hook and volumes hold {added:.0} B over {n} particles, the estimate \
             adds {allowed:.0} B"
        );
        assert!(
            held <= estimate,
            "{method}: the pipeline holds {held:.0} B, {estimate:.0} B estimated"
        );
    }
}
