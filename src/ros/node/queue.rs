//! The services' request queue: every request kept until it is answered, served round-robin
//! across clients, bounded per client and in all.
//!
//! DDS hands the node requests as they arrive; a slow answer (a batch of many states) must not
//! let later requests be overwritten or one client's burst keep everybody else waiting. The
//! node therefore moves each request off the DDS reader at once into this queue, and one worker
//! takes them out in turn: one request of each client that has any, then the next round
//! ([`FairQueue::pop`]). The queue holds at most `service_queue_per_client` requests of one
//! client and `service_queue_total` in all; a request past either limit is not dropped but
//! answered at once with `valid: false` and the reason ([`Full`]).

use std::collections::{HashMap, VecDeque};
use std::hash::Hash;
use std::sync::{Condvar, Mutex};
use std::time::Duration;

/// How many requests the queue holds: per client, and in all.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Requests of one client waiting at once (`service_queue_per_client`).
    pub per_client: usize,
    /// Requests waiting at once, all clients together (`service_queue_total`).
    pub total: usize,
}

/// Why a request was not queued: which limit it met.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Full {
    /// Its client has `per_client` requests waiting already.
    Client(usize),
    /// `total` requests are waiting already.
    Total(usize),
}

impl Full {
    /// The status a refused request is answered with: what was full, and the parameter.
    pub fn reason(self) -> String {
        match self {
            Full::Client(n) => format!(
                "request refused: {n} requests of this client already waiting \
                 (service_queue_per_client); send fewer at once"
            ),
            Full::Total(n) => format!(
                "request refused: {n} requests already waiting from all clients \
                 (service_queue_total); try again later"
            ),
        }
    }
}

/// Requests by client, taken out round-robin: one of each waiting client in turn, in the order
/// the clients first had one waiting.
pub struct FairQueue<C, T> {
    limits: Limits,
    waiting: HashMap<C, VecDeque<T>>,
    /// Clients with requests waiting, the next to be served first.
    turn: VecDeque<C>,
    len: usize,
}

impl<C: Clone + Eq + Hash, T> FairQueue<C, T> {
    /// An empty queue holding at most `limits`.
    pub fn new(limits: Limits) -> Self {
        Self {
            limits,
            waiting: HashMap::new(),
            turn: VecDeque::new(),
            len: 0,
        }
    }

    /// Queues `item` of `client`, or says which limit refuses it (giving the item back).
    pub fn push(&mut self, client: C, item: T) -> Result<(), (Full, T)> {
        if self.len >= self.limits.total {
            return Err((Full::Total(self.limits.total), item));
        }
        let queue = self.waiting.entry(client.clone()).or_default();
        if queue.len() >= self.limits.per_client {
            return Err((Full::Client(self.limits.per_client), item));
        }
        if queue.is_empty() {
            self.turn.push_back(client);
        }
        queue.push_back(item);
        self.len += 1;
        Ok(())
    }

    /// The oldest request of the client whose turn it is; that client goes to the back of the
    /// line if it has more waiting.
    pub fn pop(&mut self) -> Option<T> {
        let client = self.turn.pop_front()?;
        let queue = self.waiting.get_mut(&client)?;
        let item = queue.pop_front();
        if queue.is_empty() {
            self.waiting.remove(&client);
        } else {
            self.turn.push_back(client);
        }
        self.len -= usize::from(item.is_some());
        item
    }

    /// Requests waiting, all clients together.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no request is waiting.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// A [`FairQueue`] shared between the DDS side, which fills it, and the worker thread, which
/// empties it.
pub struct SharedQueue<C, T> {
    queue: Mutex<FairQueue<C, T>>,
    ready: Condvar,
}

impl<C: Clone + Eq + Hash, T> SharedQueue<C, T> {
    /// An empty queue holding at most `limits`.
    pub fn new(limits: Limits) -> Self {
        Self {
            queue: Mutex::new(FairQueue::new(limits)),
            ready: Condvar::new(),
        }
    }

    /// The limits the queue holds its requests to.
    pub fn limits(&self) -> Limits {
        self.lock().limits
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, FairQueue<C, T>> {
        self.queue.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Queues `item` of `client` and wakes the worker, or gives it back with the limit met.
    pub fn push(&self, client: C, item: T) -> Result<(), (Full, T)> {
        self.lock().push(client, item)?;
        self.ready.notify_one();
        Ok(())
    }

    /// The next request in turn, waiting up to `timeout` for one.
    pub fn pop_timeout(&self, timeout: Duration) -> Option<T> {
        let mut queue = self.lock();
        if queue.is_empty() {
            queue = self
                .ready
                .wait_timeout(queue, timeout)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
        queue.pop()
    }

    /// Requests waiting now.
    pub fn waiting(&self) -> usize {
        self.lock().len()
    }

    /// Wakes the worker (when the node stops).
    pub fn wake(&self) {
        self.ready.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMITS: Limits = Limits {
        per_client: 3,
        total: 5,
    };

    #[test]
    fn clients_are_served_in_turn_not_one_queue_after_another() {
        let mut q = FairQueue::new(Limits {
            per_client: 10,
            total: 100,
        });
        for i in 0..4 {
            q.push('a', ('a', i)).unwrap();
        }
        q.push('b', ('b', 0)).unwrap();
        q.push('c', ('c', 0)).unwrap();
        q.push('b', ('b', 1)).unwrap();
        let order: Vec<_> = std::iter::from_fn(|| q.pop()).collect();
        assert_eq!(
            order,
            [
                ('a', 0),
                ('b', 0),
                ('c', 0),
                ('a', 1),
                ('b', 1),
                ('a', 2),
                ('a', 3)
            ]
        );
        assert!(q.is_empty());
        // A client whose queue ran empty joins the back of the line again.
        q.push('c', ('c', 1)).unwrap();
        q.push('a', ('a', 4)).unwrap();
        assert_eq!(q.pop(), Some(('c', 1)));
        assert_eq!(q.pop(), Some(('a', 4)));
        assert_eq!(q.pop(), None);
    }

    #[test]
    fn requests_past_a_limit_are_given_back_with_the_limit_met() {
        let mut q = FairQueue::new(LIMITS);
        for i in 0..3 {
            q.push('a', i).unwrap();
        }
        assert_eq!(q.push('a', 3), Err((Full::Client(3), 3)));
        q.push('b', 10).unwrap();
        q.push('c', 20).unwrap();
        assert_eq!(q.len(), 5);
        assert_eq!(q.push('d', 30), Err((Full::Total(5), 30)));
        // Served ones make room again.
        assert_eq!(q.pop(), Some(0));
        q.push('d', 30).unwrap();
        assert_eq!(q.push('e', 40), Err((Full::Total(5), 40)));
        assert!(Full::Client(3)
            .reason()
            .contains("service_queue_per_client"));
        assert!(Full::Total(5).reason().contains("service_queue_total"));
    }

    #[test]
    fn the_shared_queue_hands_requests_to_a_waiting_worker() {
        let q = std::sync::Arc::new(SharedQueue::new(LIMITS));
        let worker = {
            let q = q.clone();
            std::thread::spawn(move || q.pop_timeout(Duration::from_secs(30)))
        };
        std::thread::sleep(Duration::from_millis(20));
        q.push('a', 7).unwrap();
        assert_eq!(worker.join().unwrap(), Some(7));
        assert_eq!(q.pop_timeout(Duration::from_millis(1)), None);
    }
}
