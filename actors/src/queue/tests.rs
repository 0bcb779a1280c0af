//! Queue tests.

use super::*;

fn reader(id: u64, q: &Arc<QueueCore>) -> Arc<ReaderEndpoint> {
    ReaderEndpoint::new(id, &format!("r{id}/in/q"), TypeInfo::of::<i64>(), q.clone())
}

fn seqs(r: &ReaderEndpoint) -> Vec<i64> {
    let mut out = Vec::new();
    r.take(usize::MAX, &mut out);
    r.ack();
    out.iter()
        .map(|i| *i.value.downcast_ref::<i64>().unwrap())
        .collect()
}

#[test]
fn every_reader_sees_every_item_once_in_order_and_items_are_freed() {
    let q = QueueCore::new("p/out/q", TypeInfo::of::<i64>(), 16);
    let (a, b) = (reader(1, &q), reader(2, &q));
    for i in 0..5 {
        q.push(Arc::new(i as i64), Instant::now());
    }
    assert_eq!(seqs(&a), vec![0, 1, 2, 3, 4]);
    assert_eq!(seqs(&a), Vec::<i64>::new());
    assert_eq!(q.len(), 5, "b has not read yet");
    assert_eq!(seqs(&b), vec![0, 1, 2, 3, 4]);
    assert_eq!(q.len(), 0, "freed once both consumed");
}

#[test]
fn unacknowledged_items_are_delivered_again_after_a_rewind() {
    let q = QueueCore::new("p/out/q", TypeInfo::of::<i64>(), 16);
    let r = reader(1, &q);
    for i in 0..4 {
        q.push(Arc::new(i as i64), Instant::now());
    }
    assert_eq!(seqs(&r), vec![0, 1, 2, 3]);
    q.push(Arc::new(4_i64), Instant::now());
    q.push(Arc::new(5_i64), Instant::now());
    let mut taken = Vec::new();
    r.take(usize::MAX, &mut taken);
    assert_eq!(
        taken.len(),
        2,
        "a step takes 4 and 5, then fails before acknowledging"
    );
    assert_eq!(q.len(), 2, "unacknowledged items are kept");
    r.rewind();
    assert_eq!(seqs(&r), vec![4, 5], "the restarted reader gets them again");
    assert_eq!(q.len(), 0);
}

#[test]
fn lagging_reader_loses_oldest_items_and_counts_them() {
    let q = QueueCore::new("p/out/q", TypeInfo::of::<i64>(), 3);
    let r = reader(1, &q);
    for i in 0..10 {
        q.push(Arc::new(i as i64), Instant::now());
    }
    assert_eq!(seqs(&r), vec![7, 8, 9]);
    assert_eq!(*r.dropped.value().downcast_ref::<i64>().unwrap(), 7);
}

/// A reader that lags for good is logged once a second with the count since, not once per push.
#[test]
fn a_lagging_reader_is_logged_at_most_once_a_second() {
    let start = Instant::now();
    let at = |ms: u64| start + std::time::Duration::from_millis(ms);
    let mut lag = LagReport::default();
    assert_eq!(lag.note(1, at(0)), Some(1));
    for ms in 1..1000 {
        assert_eq!(lag.note(2, at(ms)), None, "{ms} ms");
    }
    assert_eq!(lag.note(1, at(1000)), Some(2 * 999 + 1));
    assert_eq!(lag.note(1, at(1500)), None);
    assert_eq!(lag.note(3, at(2000)), Some(4));
}

#[test]
fn subscribed_reader_is_signalled_and_retarget_starts_at_tail() {
    let q1 = QueueCore::new("p/out/a", TypeInfo::of::<i64>(), 8);
    let q2 = QueueCore::new("p/out/b", TypeInfo::of::<i64>(), 8);
    let r = reader(1, &q1);
    let s = Arc::new(Signal::default());
    r.subscribe(&s);
    q2.push(Arc::new(100_i64), Instant::now());
    q1.push(Arc::new(1_i64), Instant::now());
    assert_eq!(s.take(), cause::ITEMS);
    r.retarget(q2.clone());
    assert_eq!(q1.len(), 0, "detaching frees what only this reader held");
    q2.push(Arc::new(101_i64), Instant::now());
    assert_eq!(s.take(), cause::ITEMS);
    assert_eq!(seqs(&r), vec![101]);
}

#[test]
fn an_item_nobody_reads_is_not_made_and_one_read_is_delivered() {
    let q = QueueCore::new("w/out/q", TypeInfo::of::<i64>(), 8);
    let made = std::cell::Cell::new(0);
    let make = |v: i64| {
        made.set(made.get() + 1);
        Arc::new(v) as AnyValue
    };
    q.push_with(|| make(1), Instant::now());
    assert_eq!(made.get(), 0, "no reader: not made");
    let r = reader(1, &q);
    q.push_with(|| make(2), Instant::now());
    assert_eq!(made.get(), 1);
    assert_eq!(seqs(&r), [2]);
    drop(r);
    q.push_with(|| make(3), Instant::now());
    assert_eq!(made.get(), 1, "the reader left: not made");
}

#[test]
fn an_acknowledgement_with_nothing_taken_changes_nothing() {
    let q = QueueCore::new("w/out/q", TypeInfo::of::<i64>(), 8);
    let r = reader(1, &q);
    r.ack();
    q.push(Arc::new(1_i64), Instant::now());
    r.ack();
    let mut out = Vec::new();
    r.take(usize::MAX, &mut out);
    assert_eq!(out.len(), 1, "acknowledging before taking skips nothing");
    r.rewind();
    out.clear();
    r.take(usize::MAX, &mut out);
    assert_eq!(out.len(), 1, "taken but not acknowledged: delivered again");
    r.ack();
    r.rewind();
    out.clear();
    r.take(usize::MAX, &mut out);
    assert!(out.is_empty(), "acknowledged: not delivered again");
}
