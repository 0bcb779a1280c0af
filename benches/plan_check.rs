//! `plan_check`: `petrel plan check` must grow linearly with a plan's length. Linear text
//! plans of 1,000 and 100,000 actions (`a0; a1; ...`) are checked with the default budget; the
//! time ratio would be 100× if linear (goal ≤ 150×). A counting global allocator gives the
//! peak of bytes allocated during one check, above what the plan itself holds (goal ≤ 200 MB
//! for 100,000 actions); both figures are printed before criterion's.

use std::alloc::{GlobalAlloc, Layout, System};
use std::hint::black_box;
use std::sync::atomic::{AtomicUsize, Ordering};

use criterion::{criterion_group, criterion_main, Criterion};
use petrel_plans::{check, compile_text, Plan};

/// The system allocator, counting live bytes and their peak.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(live, Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

fn linear(actions: usize) -> Plan {
    let src: Vec<String> = (0..actions).map(|i| format!("a{i}")).collect();
    compile_text(&src.join("; "), "linear.plan", "linear", None).expect("the linear plan compiles")
}

/// Bytes allocated at the peak of one check, above those live before it.
fn peak_bytes(plan: &Plan) -> usize {
    let before = LIVE.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    let report = check(plan);
    assert!(report.is_ok() && report.complete, "{report}");
    PEAK.load(Ordering::Relaxed) - before
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("plan_check");
    group.sample_size(10);
    for (name, actions) in [("linear_1k", 1_000), ("linear_100k", 100_000)] {
        let plan = linear(actions);
        let report = check(&plan);
        assert_eq!(report.states, 2 * actions + 1, "{report}");
        println!(
            "plan_check/{name}: {} markings, peak {:.1} MB allocated by one check",
            report.states,
            peak_bytes(&plan) as f64 / 1e6
        );
        group.bench_function(name, |b| b.iter(|| black_box(check(black_box(&plan)))));
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
