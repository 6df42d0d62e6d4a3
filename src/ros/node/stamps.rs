//! Scan stamp ordering: which scans arrive too late to score, and when time has jumped back.
//!
//! The node scores scans in stamp order: a scan stamped a little older than one already scored
//! is a late delivery and is skipped. But a stamp far older than the newest one scored is not a
//! late scan, it is time going back — a simulation reset that restarts its clock at 0, a bag
//! played again, a far-future stamp scored once by mistake. As ROS does on a backward time jump
//! (tf2 clears its buffer), the node then starts the ordering again from that scan, once it is
//! scored. Only a scored scan moves the newest stamp, so a rejected one (malformed, far in the
//! future or far back) never holds back or resets the scans after it.

use crate::ros::messages::Time;

/// What a scan's stamp says about it, against the newest stamp scored.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Order {
    /// As new as every scan scored, or newer (or the first): score it.
    Newest,
    /// Older than the newest scored by no more than the tolerance: a late delivery, skipped.
    Late,
    /// Older by more than the tolerance, by this many seconds: time jumped back. Score it; once
    /// scored, the ordering starts again from it.
    JumpedBack(f64),
}

/// The newest stamp among the scans scored (none at first).
#[derive(Debug, Clone, Default)]
pub struct StampOrder {
    newest: Option<Time>,
}

impl StampOrder {
    /// Where `stamp` stands: more than `tolerance` seconds older than the newest scored means
    /// that time jumped back.
    pub fn check(&self, stamp: Time, tolerance: f64) -> Order {
        let Some(newest) = self.newest.filter(|newest| stamp < *newest) else {
            return Order::Newest;
        };
        let behind = newest.seconds() - stamp.seconds();
        if behind > tolerance {
            Order::JumpedBack(behind)
        } else {
            Order::Late
        }
    }

    /// Records that a scan stamped `stamp`, [`Order::Newest`] or [`Order::JumpedBack`], was
    /// scored: it is the newest now.
    pub fn scored(&mut self, stamp: Time) {
        self.newest = Some(stamp);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(sec: i32, nanosec: u32) -> Time {
        Time { sec, nanosec }
    }

    #[test]
    fn only_scored_scans_advance_the_order() {
        let mut order = StampOrder::default();
        assert_eq!(order.check(at(i32::MAX, 0), 1.0), Order::Newest);
        // That scan was rejected (never scored): it does not hold back the next ones.
        assert_eq!(order.check(at(10, 0), 1.0), Order::Newest);
        order.scored(at(10, 0));
        assert_eq!(order.check(at(10, 0), 1.0), Order::Newest);
        assert_eq!(order.check(at(11, 0), 1.0), Order::Newest);
    }

    #[test]
    fn a_little_older_is_late_much_older_is_a_jump_back_that_restarts_the_order() {
        let mut order = StampOrder::default();
        order.scored(at(100, 500_000_000));
        assert_eq!(order.check(at(100, 0), 1.0), Order::Late);
        assert_eq!(order.check(at(99, 500_000_000), 1.0), Order::Late); // exactly the tolerance
        let Order::JumpedBack(by) = order.check(at(0, 0), 1.0) else {
            panic!("a clock restarting at 0 is a jump back");
        };
        assert!((by - 100.5).abs() < 1e-9, "{by}");
        // Until a scan of the new time line is scored, nothing changed (a rejected one resets
        // nothing); once one is, the order goes on from it.
        assert_eq!(order.check(at(100, 0), 1.0), Order::Late);
        order.scored(at(0, 0));
        assert_eq!(order.check(at(0, 100), 1.0), Order::Newest);
        assert_eq!(order.check(at(99, 0), 1.0), Order::Newest);
        assert!(matches!(order.check(at(100, 0), 1.0), Order::Newest));
    }

    #[test]
    fn a_far_future_stamp_scored_by_mistake_holds_back_nothing() {
        let mut order = StampOrder::default();
        order.scored(at(i32::MAX, 999_999_999));
        assert!(matches!(
            order.check(at(1000, 0), 1.0),
            Order::JumpedBack(_)
        ));
        order.scored(at(1000, 0));
        assert_eq!(order.check(at(1001, 0), 1.0), Order::Newest);
    }

    #[test]
    fn the_tolerance_is_the_callers() {
        let mut order = StampOrder::default();
        order.scored(at(10, 0));
        assert_eq!(order.check(at(7, 0), 5.0), Order::Late);
        assert_eq!(order.check(at(7, 0), 2.0), Order::JumpedBack(3.0));
    }
}
