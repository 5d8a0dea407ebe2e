//! Bounded queues between the concurrent stages of the live pipeline.
//!
//! Capture, pose (segmentation + descriptors + regression), cloth and compositing run on their own
//! threads, joined by [`StageQueue`]s. A queue holds at most `capacity` items and has one of two
//! policies when it is full:
//!
//! * [`Full::DropOldest`] — the producer never waits; the oldest waiting item is thrown away and
//!   counted. The camera feeds the pose stage this way, so when the machine falls behind the picture
//!   shows the newest frame rather than one from a second ago.
//! * [`Full::Wait`] — the producer blocks until there is room (back-pressure). Recorded input uses it
//!   everywhere so no frame is lost, and the later live stages use it so that every pose that was
//!   estimated is also recorded.
//!
//! Closing a queue (the producer is done, or the consumer quit) wakes everyone up: `pop` drains what
//! is left and then returns `None`; `push` into a queue whose consumer is gone returns the item.
//! Plain `std` mutex and condition variables: the queues carry a few frames a second per stage, far
//! from where a lock-free queue would pay.

use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};

/// What a full queue does with a new item.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Full {
    DropOldest,
    Wait,
}

struct State<T> {
    items: VecDeque<T>,
    dropped: u64,
    closed: bool,
}

struct Shared<T> {
    state: Mutex<State<T>>,
    changed: Condvar,
    capacity: usize,
    policy: Full,
}

/// A bounded multi-producer, multi-consumer queue; clones share the same queue.
pub struct StageQueue<T> {
    shared: Arc<Shared<T>>,
}

impl<T> Clone for StageQueue<T> {
    fn clone(&self) -> Self {
        StageQueue {
            shared: Arc::clone(&self.shared),
        }
    }
}

impl<T> StageQueue<T> {
    /// A queue of at most `capacity` (≥ 1) items.
    pub fn new(capacity: usize, policy: Full) -> StageQueue<T> {
        StageQueue {
            shared: Arc::new(Shared {
                state: Mutex::new(State {
                    items: VecDeque::with_capacity(capacity.max(1)),
                    dropped: 0,
                    closed: false,
                }),
                changed: Condvar::new(),
                capacity: capacity.max(1),
                policy,
            }),
        }
    }

    fn lock(&self) -> MutexGuard<'_, State<T>> {
        // A panicking stage thread poisons the lock; the queue's own state is still consistent
        // (every critical section below leaves it valid), so carry on with it.
        self.shared
            .state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Adds an item. Returns it back when the queue is closed.
    pub fn push(&self, item: T) -> Result<(), T> {
        let mut state = self.lock();
        loop {
            if state.closed {
                return Err(item);
            }
            if state.items.len() < self.shared.capacity {
                break;
            }
            match self.shared.policy {
                Full::DropOldest => {
                    state.items.pop_front();
                    state.dropped += 1;
                    break;
                }
                Full::Wait => {
                    state = self
                        .shared
                        .changed
                        .wait(state)
                        .unwrap_or_else(|poisoned| poisoned.into_inner());
                }
            }
        }
        state.items.push_back(item);
        drop(state);
        self.shared.changed.notify_all();
        Ok(())
    }

    /// Takes the oldest item, waiting for one; `None` once the queue is closed and empty.
    pub fn pop(&self) -> Option<T> {
        let mut state = self.lock();
        loop {
            if let Some(item) = state.items.pop_front() {
                drop(state);
                self.shared.changed.notify_all();
                return Some(item);
            }
            if state.closed {
                return None;
            }
            state = self
                .shared
                .changed
                .wait(state)
                .unwrap_or_else(|poisoned| poisoned.into_inner());
        }
    }

    /// Takes the oldest item if there is one, without waiting.
    pub fn try_pop(&self) -> Option<T> {
        let item = self.lock().items.pop_front();
        if item.is_some() {
            self.shared.changed.notify_all();
        }
        item
    }

    /// No more items will come (or none are wanted): wakes every waiting thread.
    pub fn close(&self) {
        self.lock().closed = true;
        self.shared.changed.notify_all();
    }

    pub fn is_closed(&self) -> bool {
        self.lock().closed
    }

    /// Items thrown away by [`Full::DropOldest`] so far.
    pub fn dropped(&self) -> u64 {
        self.lock().dropped
    }

    pub fn len(&self) -> usize {
        self.lock().items.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::thread;

    #[test]
    fn a_full_drop_oldest_queue_keeps_the_newest_and_counts_the_rest() {
        let q = StageQueue::new(2, Full::DropOldest);
        for i in 0..5 {
            assert_eq!(q.push(i), Ok(()));
        }
        assert_eq!(q.dropped(), 3);
        assert_eq!(q.pop(), Some(3));
        assert_eq!(q.pop(), Some(4));
        assert_eq!(q.try_pop(), None);
    }

    #[test]
    fn a_waiting_queue_loses_nothing_and_keeps_order() {
        let q = StageQueue::new(1, Full::Wait);
        let producer = {
            let q = q.clone();
            thread::spawn(move || {
                for i in 0..200 {
                    assert_eq!(q.push(i), Ok(()));
                }
                q.close();
            })
        };
        let received: Vec<i32> = std::iter::from_fn(|| q.pop()).collect();
        producer.join().expect("producer");
        assert_eq!(received, (0..200).collect::<Vec<_>>());
        assert_eq!(q.dropped(), 0);
    }

    #[test]
    fn closing_drains_then_ends_and_refuses_new_items() {
        let q = StageQueue::new(3, Full::Wait);
        q.push("a").expect("open");
        q.close();
        assert_eq!(q.push("b"), Err("b"));
        assert_eq!(q.pop(), Some("a"));
        assert_eq!(q.pop(), None);
    }

    #[test]
    fn closing_wakes_a_blocked_producer() {
        let q = StageQueue::new(1, Full::Wait);
        q.push(1).expect("room");
        let blocked = {
            let q = q.clone();
            thread::spawn(move || q.push(2))
        };
        thread::sleep(std::time::Duration::from_millis(20));
        q.close();
        assert_eq!(blocked.join().expect("thread"), Err(2));
    }
}
