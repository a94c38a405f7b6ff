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
    #[should_panic]
    fn out_of_bounds_panics() {
        let mut v = [0.0; 2];
        let owner = [0, 0];
        let [mut a, _] = PartSlice::split(&mut v, &owner);
        *a.get(2) = 1.0;
    }
}
