//! The request memories FIFO_Kabina and FIFO_Patra (§6.5, table 6.1 of the lift thesis: `INT[4]`).
//!
//! The lift thesis' program loads them with the FIFO Load instruction and unloads the next target
//! with FIFO Unload when the cabin stands at its target. docs/controller.md adds: a floor already
//! queued is not queued again. A full memory refuses the request, as FFL does when its done bit is
//! set.

/// What happened to a request offered to a [`RequestFifo`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Offer {
    /// Stored at the back.
    Stored,
    /// The floor is queued already.
    AlreadyQueued,
    /// All places are taken; the request is lost.
    Full,
}

/// A FIFO of floor numbers with no duplicates and `N` places.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RequestFifo<const N: usize> {
    items: [u8; N],
    len: usize,
}

impl<const N: usize> Default for RequestFifo<N> {
    fn default() -> Self {
        RequestFifo {
            items: [0; N],
            len: 0,
        }
    }
}

impl<const N: usize> RequestFifo<N> {
    /// An empty memory.
    pub fn new() -> Self {
        Self::default()
    }

    /// Offers `floor`; see [`Offer`].
    pub fn offer(&mut self, floor: u8) -> Offer {
        if self.contains(floor) {
            Offer::AlreadyQueued
        } else if self.len == N {
            Offer::Full
        } else {
            self.items[self.len] = floor;
            self.len += 1;
            Offer::Stored
        }
    }

    /// Offers `floor` at the front (a request given back): it is unloaded next. A full memory
    /// drops its newest entry to make room.
    pub fn offer_front(&mut self, floor: u8) -> Offer {
        if self.contains(floor) {
            self.remove(floor);
        } else if self.len == N {
            self.len -= 1;
        }
        if N == 0 {
            return Offer::Full;
        }
        self.items.copy_within(0..self.len, 1);
        self.items[0] = floor;
        self.len += 1;
        Offer::Stored
    }

    /// Takes the oldest floor out (FIFO Unload).
    pub fn unload(&mut self) -> Option<u8> {
        if self.len == 0 {
            return None;
        }
        let first = self.items[0];
        self.items.copy_within(1..self.len, 0);
        self.len -= 1;
        Some(first)
    }

    /// Removes `floor` wherever it is; `true` if it was queued.
    pub fn remove(&mut self, floor: u8) -> bool {
        let Some(i) = self.as_slice().iter().position(|f| *f == floor) else {
            return false;
        };
        self.items.copy_within(i + 1..self.len, i);
        self.len -= 1;
        true
    }

    /// `true` if `floor` is queued.
    pub fn contains(&self, floor: u8) -> bool {
        self.as_slice().contains(&floor)
    }

    /// The queued floors, oldest first.
    pub fn as_slice(&self) -> &[u8] {
        &self.items[..self.len]
    }

    /// Number of queued floors.
    pub fn len(&self) -> usize {
        self.len
    }

    /// `true` if nothing is queued.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_in_first_out_without_duplicates_and_four_places() {
        let mut f = RequestFifo::<4>::new();
        assert_eq!(f.offer(3), Offer::Stored);
        assert_eq!(f.offer(1), Offer::Stored);
        assert_eq!(f.offer(3), Offer::AlreadyQueued);
        assert_eq!(f.offer(4), Offer::Stored);
        assert_eq!(f.offer(2), Offer::Stored);
        assert_eq!(f.offer(5), Offer::Full);
        assert_eq!(f.as_slice(), &[3, 1, 4, 2]);
        assert_eq!(f.unload(), Some(3));
        assert!(f.remove(4));
        assert!(!f.remove(4));
        assert_eq!(f.as_slice(), &[1, 2]);
        assert_eq!(f.unload(), Some(1));
        assert_eq!(f.unload(), Some(2));
        assert_eq!(f.unload(), None);
    }

    #[test]
    fn a_request_given_back_goes_first() {
        let mut f = RequestFifo::<4>::new();
        f.offer(2);
        f.offer(3);
        assert_eq!(f.offer_front(4), Offer::Stored);
        assert_eq!(f.offer_front(3), Offer::Stored);
        assert_eq!(f.as_slice(), &[3, 4, 2]);
        f.offer(1);
        f.offer_front(5);
        assert_eq!(f.as_slice(), &[5, 3, 4, 2]);
    }
}
