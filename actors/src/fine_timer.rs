//! A timer finer than tokio's, for periodic modules: one thread per process sleeps to the
//! earliest deadline and wakes the task waiting for it.
//!
//! Why: tokio's timer wheel has 1 ms slots and its driver sleeps in `epoll_wait`, whose timeout
//! is in whole milliseconds, so a 1 kHz module's period strayed by up to a millisecond (p99
//! 1 ms even alone). Here a condition variable's timed wait (a futex with a nanosecond
//! timeout, the thread's timer slack lowered to 1 µs) ends within microseconds of the
//! deadline; the task is then woken like by any other thread. No thread spins: between
//! deadlines the timer thread sleeps.
//!
//! Only for runtimes whose clock cannot be paused (see [`fine_clock_here`]): a paused test
//! clock must keep driving periodic modules through tokio's timer.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;
use std::task::{Context, Poll, Waker};
use std::time::{Duration, Instant};

use parking_lot::{Condvar, Mutex};

thread_local! {
    /// Set on an agent's own thread, whose runtime petrel built and never pauses.
    static ON_AGENT_THREAD: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Marks the current thread as an agent's own (see [`fine_clock_here`]).
pub(crate) fn mark_agent_thread() {
    ON_AGENT_THREAD.with(|c| c.set(true));
}

/// Whether periodic modules on the current runtime may use the fine timer: tokio pauses a
/// clock only on a current-thread runtime, and petrel's agent threads never pause theirs. A
/// current-thread runtime elsewhere (a paused-clock test) keeps tokio's timer.
pub(crate) fn fine_clock_here() -> bool {
    if ON_AGENT_THREAD.with(|c| c.get()) {
        return true;
    }
    tokio::runtime::Handle::try_current()
        .is_ok_and(|h| h.runtime_flavor() != tokio::runtime::RuntimeFlavor::CurrentThread)
}

/// The deadlines waited for, earliest first, and who waits for each.
#[derive(Default)]
struct Deadlines {
    heap: BinaryHeap<Reverse<(Instant, u64)>>,
    /// By sleep id: its deadline and its task's waker. A heap entry whose id is gone here (the
    /// sleep ended or moved its deadline) is skipped when it comes up.
    waiting: HashMap<u64, (Instant, Waker)>,
}

struct Timer {
    deadlines: Mutex<Deadlines>,
    earlier: Condvar,
    /// The timer thread, which runs as long as the process.
    thread: OnceLock<libc::pthread_t>,
    /// The highest real-time priority asked for so far (0: none).
    priority: Mutex<u8>,
}

fn timer() -> &'static Timer {
    static TIMER: OnceLock<&'static Timer> = OnceLock::new();
    TIMER.get_or_init(|| {
        let timer: &'static Timer = Box::leak(Box::new(Timer {
            deadlines: Mutex::new(Deadlines::default()),
            earlier: Condvar::new(),
            thread: OnceLock::new(),
            priority: Mutex::new(0),
        }));
        let thread = std::thread::Builder::new()
            .name("petrel-fine-timer".into())
            .spawn(move || timer.run())
            .expect("the fine timer thread could not be started");
        let _ = timer
            .thread
            .set(std::os::unix::thread::JoinHandleExt::as_pthread_t(&thread));
        timer
    })
}

/// Starts the timer thread now, if it is not running yet. A thread inherits its creator's nice
/// value, and a lowered one cannot be raised back without a privilege: the timer must not be
/// started first by a tick of a module on threads set below the agent's (`long_step_threads`).
pub(crate) fn start() {
    timer();
}

/// Runs the timer thread under `SCHED_FIFO` at `priority`, unless it runs at a higher one
/// already (agents of one process may ask for different ones: the timer serves them all).
pub(crate) fn raise_priority(priority: u8) -> std::io::Result<()> {
    let timer = timer();
    let mut applied = timer.priority.lock();
    if priority <= *applied {
        return Ok(());
    }
    let thread = *timer.thread.get().expect("set when the timer started");
    crate::realtime::set_fifo(thread, priority)?;
    *applied = priority;
    Ok(())
}

impl Timer {
    fn run(&self) {
        // The kernel may end a timed sleep up to the thread's timer slack late (50 µs by
        // default): ask for 1 µs. Refused, the timer is only coarser.
        // SAFETY: prctl with PR_SET_TIMERSLACK takes a plain integer.
        unsafe {
            libc::prctl(libc::PR_SET_TIMERSLACK, 1000_u64, 0, 0, 0);
        }
        let mut due: Vec<Waker> = Vec::new();
        let mut d = self.deadlines.lock();
        loop {
            let now = Instant::now();
            while let Some(&Reverse((at, id))) = d.heap.peek() {
                if at > now {
                    break;
                }
                d.heap.pop();
                if d.waiting.get(&id).is_some_and(|(wanted, _)| *wanted == at) {
                    if let Some((_, waker)) = d.waiting.remove(&id) {
                        due.push(waker);
                    }
                }
            }
            let next = d.heap.peek().map(|Reverse((at, _))| *at);
            if !due.is_empty() {
                // Wake outside the lock: a woken task may register its next deadline at once.
                drop(d);
                due.drain(..).for_each(Waker::wake);
                d = self.deadlines.lock();
                continue;
            }
            match next {
                Some(at) => {
                    self.earlier.wait_until(&mut d, at);
                }
                None => self.earlier.wait(&mut d),
            }
        }
    }
}

/// A fresh id to register deadlines under.
fn new_id() -> u64 {
    static NEXT_ID: AtomicU64 = AtomicU64::new(1);
    NEXT_ID.fetch_add(1, Ordering::Relaxed)
}

/// Registers `deadline` and `waker` under `id`, or moves `id`'s registration there; wakes the
/// timer thread when the deadline is the earliest.
fn register(id: u64, deadline: Instant, waker: &Waker) {
    let timer = timer();
    let mut d = timer.deadlines.lock();
    let first = d.heap.peek().is_none_or(|Reverse((at, _))| deadline < *at);
    match d.waiting.get_mut(&id) {
        Some((at, w)) if *at == deadline => w.clone_from(waker),
        _ => {
            d.waiting.insert(id, (deadline, waker.clone()));
            d.heap.push(Reverse((deadline, id)));
        }
    }
    drop(d);
    if first {
        timer.earlier.notify_one();
    }
}

/// Forgets `id`'s registration; its heap entry is skipped when it comes up.
fn deregister(id: u64) {
    timer().deadlines.lock().waiting.remove(&id);
}

/// A period on the fine timer, like tokio's `interval` with `MissedTickBehavior::Skip`: the
/// first tick one period from now, ticks missed while the module was busy are skipped, and the
/// ticks stay on the grid of the start time.
///
/// Its registration with the timer outlives a wait that is given up: a periodic module that
/// data woke between two ticks waits again for the same tick without touching the timer.
/// (A sleep per wait cost a lock, a table insert and a heap entry at every wake-up, and the
/// heap grew by one entry per wake-up until the tick: millions for a module woken at a high
/// rate with a long period.)
pub(crate) struct FineTicker {
    next: Instant,
    period: Duration,
    id: u64,
    /// The deadline registered under `id` and the waker given with it, if any.
    registered: Option<(Instant, Waker)>,
}

impl FineTicker {
    pub fn new(period: Duration) -> Self {
        FineTicker {
            next: Instant::now() + period,
            period,
            id: new_id(),
            registered: None,
        }
    }

    /// Waits for the next tick.
    pub async fn tick(&mut self) {
        std::future::poll_fn(|cx| self.poll_due(cx)).await;
        self.next = next_tick(self.next, self.period, Instant::now());
    }

    fn poll_due(&mut self, cx: &mut Context<'_>) -> Poll<()> {
        if Instant::now() >= self.next {
            return Poll::Ready(());
        }
        let current = self
            .registered
            .as_ref()
            .is_some_and(|(at, waker)| *at == self.next && waker.will_wake(cx.waker()));
        if !current {
            register(self.id, self.next, cx.waker());
            self.registered = Some((self.next, cx.waker().clone()));
        }
        Poll::Pending
    }
}

impl Drop for FineTicker {
    fn drop(&mut self) {
        if self.registered.is_some() {
            deregister(self.id);
        }
    }
}

/// The first tick on the grid `last + k·period` (k ≥ 1) after `now`.
fn next_tick(last: Instant, period: Duration, now: Instant) -> Instant {
    let next = last + period;
    if next > now || period.is_zero() {
        return next;
    }
    let behind = now.duration_since(last).as_nanos();
    let periods = behind / period.as_nanos() + 1;
    last + period * u32::try_from(periods).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missed_ticks_are_skipped_and_the_grid_kept() {
        let t0 = Instant::now();
        let ms = Duration::from_millis(1);
        assert_eq!(next_tick(t0, ms, t0), t0 + ms);
        assert_eq!(next_tick(t0, ms, t0 + ms / 2), t0 + ms);
        assert_eq!(next_tick(t0, ms, t0 + ms), t0 + 2 * ms);
        assert_eq!(next_tick(t0, ms, t0 + ms * 5 + ms / 3), t0 + 6 * ms);
    }

    #[test]
    fn only_runtimes_that_cannot_be_paused_use_the_fine_timer() {
        let current = tokio::runtime::Builder::new_current_thread()
            .build()
            .unwrap();
        assert!(
            !current.block_on(async { fine_clock_here() }),
            "a test clock may be paused"
        );
        let multi = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .build()
            .unwrap();
        assert!(multi.block_on(async { fine_clock_here() }));
        let agent = std::thread::spawn(move || {
            mark_agent_thread();
            current.block_on(async { fine_clock_here() })
        });
        assert!(agent.join().unwrap(), "an agent's own thread");
    }

    #[test]
    fn a_tick_comes_at_its_time_not_before() {
        let rt = tokio::runtime::Builder::new_current_thread()
            .build()
            .unwrap();
        for micros in [1, 300, 1500] {
            let period = Duration::from_micros(micros);
            let start = Instant::now();
            let mut ticker = FineTicker::new(period);
            rt.block_on(ticker.tick());
            assert!(Instant::now() >= start + period);
        }
    }

    /// The entries of the timer's heap registered under `id`.
    fn heap_entries(id: u64) -> usize {
        let d = timer().deadlines.lock();
        d.heap.iter().filter(|Reverse((_, i))| *i == id).count()
    }

    #[test]
    fn a_wait_given_up_and_taken_again_registers_once_and_a_dropped_ticker_none() {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_time()
            .build()
            .unwrap();
        rt.block_on(async {
            let mut hourly = FineTicker::new(Duration::from_secs(3600));
            let late = hourly.next;
            // As a module woken by data between two ticks: each wait is given up.
            for _ in 0..1000 {
                tokio::select! {
                    biased;
                    _ = hourly.tick() => panic!("an hour passed"),
                    _ = std::future::ready(()) => {}
                }
                tokio::select! {
                    _ = hourly.tick() => panic!("an hour passed"),
                    _ = tokio::task::yield_now() => {}
                }
            }
            assert_eq!(heap_entries(hourly.id), 1, "one registration for one tick");
            // A ticker dropped leaves no waiting deadline behind; the others stay on time.
            let mut soon = FineTicker::new(Duration::from_millis(1));
            let id = hourly.id;
            drop(hourly);
            soon.tick().await;
            let d = timer().deadlines.lock();
            assert!(!d.waiting.contains_key(&id));
            assert!(d.waiting.values().all(|(at, _)| *at != late));
        });
    }
}
