//! A slice shared out between the two parts of a separator order: each part's handle
//! reaches only the entries its part owns, so the two handles may be used on two threads
//! at once (the node updates of a two-part Newton iteration).

use std::marker::PhantomData;

/// One part's handle on a slice whose entry `i` belongs to part `owner[i]` (0 or 1).
/// [`Self::get`] of an entry the other part owns panics.
pub struct PartSlice<'a, T> {
    ptr: *mut T,
    owner: &'a [u8],
    part: u8,
    _slice: PhantomData<&'a mut [T]>,
}

// SAFETY: the two handles of one slice reach disjoint entries (checked in `get`).
unsafe impl<T: Send> Send for PartSlice<'_, T> {}

impl<'a, T> PartSlice<'a, T> {
    /// The handles of parts 0 and 1 on `data` (one owner per entry).
    pub fn split(data: &'a mut [T], owner: &'a [u8]) -> [Self; 2] {
        assert_eq!(data.len(), owner.len(), "one owner per entry");
        let ptr = data.as_mut_ptr();
        [0, 1].map(|part| Self {
            ptr,
            owner,
            part,
            _slice: PhantomData,
        })
    }

    /// Entry `i`, which this part must own.
    #[inline(always)]
    pub fn get(&mut self, i: usize) -> &mut T {
        assert!(
            self.owner[i] == self.part,
            "a part reached another part's entry"
        );
        // SAFETY: `i` is in bounds (`owner` has the slice's length); the other handle
        // cannot reach entry i (it is not its part's), and `&mut self` keeps one
        // reference of this handle alive at a time.
        unsafe { &mut *self.ptr.add(i) }
    }

    /// Entries `range`, all of which this part must own.
    #[inline]
    pub fn get_range(&mut self, range: std::ops::Range<usize>) -> &mut [T] {
        assert!(
            self.owner[range.clone()].iter().all(|&o| o == self.part),
            "a part reached another part's entry"
        );
        // SAFETY: the range is in bounds (`owner` has the slice's length, checked by the
        // indexing above); the other handle cannot reach these entries (not its part's),
        // and `&mut self` keeps one reference of this handle alive at a time.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(range.start), range.len()) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_part_writes_its_own_entries_on_its_thread() {
        let mut v = vec![0u32; 10];
        let owner: Vec<u8> = (0..10).map(|i| (i % 3 == 0) as u8).collect();
        let [mut a, mut b] = PartSlice::split(&mut v, &owner);
        std::thread::scope(|s| {
            s.spawn(move || (0..10).filter(|i| i % 3 == 0).for_each(|i| *b.get(i) = 1));
            (0..10).filter(|i| i % 3 != 0).for_each(|i| *a.get(i) = 2);
        });
        let want: Vec<u32> = (0..10).map(|i| if i % 3 == 0 { 1 } else { 2 }).collect();
        assert_eq!(v, want);
    }

    #[test]
    #[should_panic(expected = "another part's entry")]
    fn reaching_the_other_part_panics() {
        let mut v = [0.0; 4];
        let owner = [0, 1, 0, 1];
        let [mut a, _] = PartSlice::split(&mut v, &owner);
        *a.get(1) = 1.0;
    }

    #[test]
    fn a_range_of_own_entries_is_reached_and_one_of_another_part_is_not() {
        let mut v = [0u8; 6];
        let owner = [0, 0, 1, 1, 1, 0];
        let [mut a, mut b] = PartSlice::split(&mut v, &owner);
        b.get_range(2..5).fill(7);
        a.get_range(0..2).fill(1);
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| a.get_range(1..3).len()));
        assert!(r.is_err(), "entry 2 is part 1's");
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| a.get_range(5..7).len()));
        assert!(r.is_err(), "out of bounds");
        assert_eq!(v, [1, 1, 7, 7, 7, 0]);
    }

    #[test]
    #[should_panic]
    fn out_of_bounds_panics() {
        let mut v = [0.0; 2];
        let owner = [0, 0];
        let [mut a, _] = PartSlice::split(&mut v, &owner);
        *a.get(2) = 1.0;
    }
}
