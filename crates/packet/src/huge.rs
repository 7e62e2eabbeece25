//! The arrays the kernels walk, on memory the OS may back with 2 MiB pages.
//!
//! A traversal touches nodes and leaf blocks all over its arrays, a page apart more often
//! than not; with 4 KiB pages a large scene's walk waits on address translation as well as
//! on memory. On Linux, [`HugeArray`] maps arrays of at least 512 KiB on their own, as whole
//! 2 MiB pages aligned to 2 MiB, and asks for transparent huge pages
//! (`madvise(MADV_HUGEPAGE)`, honoured in Linux's default `madvise` mode) before the first
//! write, so that the pages are huge from the first fault. (Memory from the heap would not
//! do: its pages are often faulted in already, as 4 KiB ones, by earlier allocations.)
//! Smaller arrays, other systems, or a refused mapping use the global allocator: only the
//! speed differs.

use std::alloc::{self, Layout};
use std::mem::MaybeUninit;
use std::ops::{Deref, DerefMut};
use std::ptr::NonNull;

/// One huge page: the alignment and size unit of mapped arrays.
const HUGE_PAGE: usize = 2 << 20;

/// A fixed-length array of `T` (see the module).
pub(crate) struct HugeArray<T: Copy> {
    ptr: NonNull<T>,
    len: usize,
    /// Bytes mapped for it by [`os::map`], or 0 when it came from the global allocator.
    mapped: usize,
}

// SAFETY: a `HugeArray` owns its elements as a `Box<[T]>` would.
#[allow(unsafe_code)]
unsafe impl<T: Copy + Send> Send for HugeArray<T> {}
// SAFETY: as above; shared access only reads.
#[allow(unsafe_code)]
unsafe impl<T: Copy + Sync> Sync for HugeArray<T> {}

impl<T: Copy> Default for HugeArray<T> {
    fn default() -> Self {
        Self {
            ptr: NonNull::dangling(),
            len: 0,
            mapped: 0,
        }
    }
}

impl<T: Copy + Send + Sync> HugeArray<T> {
    /// `len` copies of `value`, written in parallel (so that every thread faults its part
    /// in).
    ///
    /// # Panics
    /// When the size overflows `isize`, or, as `Vec` does, when the allocation fails.
    pub fn filled(len: usize, value: T) -> Self {
        let Some(layout) = Self::heap_layout(len) else {
            return Self::default();
        };
        let mut array = Self::mapped(layout.size()).unwrap_or_else(|| {
            #[allow(unsafe_code)]
            // SAFETY: `layout` has a non-zero size (`heap_layout` returns `None` otherwise).
            let raw = unsafe { alloc::alloc(layout) };
            let Some(ptr) = NonNull::new(raw.cast::<T>()) else {
                alloc::handle_alloc_error(layout);
            };
            Self {
                ptr,
                len: 0,
                mapped: 0,
            }
        });
        #[allow(unsafe_code)]
        // SAFETY: the memory holds `len` elements of `T`, aligned, and nothing else refers
        // to it; `MaybeUninit` needs no initialised contents.
        let slots = unsafe {
            std::slice::from_raw_parts_mut(array.ptr.as_ptr().cast::<MaybeUninit<T>>(), len)
        };
        use rayon::prelude::*;
        slots.par_iter_mut().for_each(|slot| {
            slot.write(value);
        });
        array.len = len;
        array
    }

    /// A mapping of whole huge pages for `bytes` (at least a quarter of a huge page: the
    /// rest of the last page is the price), or `None` (small, not Linux, or refused).
    fn mapped(bytes: usize) -> Option<Self> {
        if bytes < HUGE_PAGE / 4 || std::mem::align_of::<T>() > HUGE_PAGE {
            return None;
        }
        let mapped = bytes.checked_next_multiple_of(HUGE_PAGE)?;
        let ptr = NonNull::new(os::map(mapped)?.cast::<T>())?;
        Some(Self {
            ptr,
            len: 0,
            mapped,
        })
    }
}

impl<T: Copy> HugeArray<T> {
    /// The global allocator's layout for `len` elements; `None` when it is empty.
    ///
    /// # Panics
    /// When the size overflows `isize`.
    fn heap_layout(len: usize) -> Option<Layout> {
        let layout = Layout::array::<T>(len).expect("array size overflows");
        (layout.size() > 0).then_some(layout)
    }
}

impl<T: Copy> Deref for HugeArray<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        #[allow(unsafe_code)]
        // SAFETY: `ptr` holds `len` initialised elements (or is dangling with `len` 0).
        unsafe {
            std::slice::from_raw_parts(self.ptr.as_ptr(), self.len)
        }
    }
}

impl<T: Copy> DerefMut for HugeArray<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        #[allow(unsafe_code)]
        // SAFETY: as in `deref`, and `&mut self` makes the access exclusive.
        unsafe {
            std::slice::from_raw_parts_mut(self.ptr.as_ptr(), self.len)
        }
    }
}

impl<T: Copy> Drop for HugeArray<T> {
    fn drop(&mut self) {
        if self.mapped > 0 {
            os::unmap(self.ptr.as_ptr().cast(), self.mapped);
        } else if let Some(layout) = Self::heap_layout(self.len) {
            #[allow(unsafe_code)]
            // SAFETY: allocated in `filled` with this layout (`T: Copy` needs no drops).
            unsafe {
                alloc::dealloc(self.ptr.as_ptr().cast(), layout);
            }
        }
    }
}

impl<T: Copy> std::fmt::Debug for HugeArray<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HugeArray")
            .field("len", &self.len)
            .field("mapped", &self.mapped)
            .finish_non_exhaustive()
    }
}

/// Linux: anonymous mappings aligned to a huge page and advised for huge pages.
#[cfg(target_os = "linux")]
#[allow(unsafe_code)]
mod os {
    use super::HUGE_PAGE;

    /// `bytes` (a multiple of [`HUGE_PAGE`]) of fresh zeroed memory aligned to
    /// [`HUGE_PAGE`], advised for transparent huge pages; `None` when refused.
    pub fn map(bytes: usize) -> Option<*mut u8> {
        let len = bytes.checked_add(HUGE_PAGE)?;
        // SAFETY: a new private anonymous mapping; no existing memory is touched.
        let raw = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                len,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                -1,
                0,
            )
        };
        if raw == libc::MAP_FAILED {
            return None;
        }
        let start = raw as usize;
        let aligned = start.next_multiple_of(HUGE_PAGE);
        let (head, tail) = (aligned - start, HUGE_PAGE - (aligned - start));
        // SAFETY: the head and the tail are the page-aligned parts of the new mapping
        // outside `aligned..aligned + bytes` (the kernel maps whole pages, so `start` and
        // `aligned + bytes` are page-aligned); nothing refers to them. The advice changes
        // how the kept part is backed, never its contents.
        unsafe {
            if head > 0 {
                libc::munmap(raw, head);
            }
            if tail > 0 {
                libc::munmap((aligned + bytes) as *mut libc::c_void, tail);
            }
            libc::madvise(aligned as *mut libc::c_void, bytes, libc::MADV_HUGEPAGE);
        }
        Some(aligned as *mut u8)
    }

    /// Unmaps what [`map`] returned.
    pub fn unmap(ptr: *mut u8, bytes: usize) {
        // SAFETY: `ptr` and `bytes` are a live mapping of `map`, whose owner is dropping it.
        unsafe {
            libc::munmap(ptr.cast(), bytes);
        }
    }
}

/// Elsewhere: no mappings (the global allocator serves every array).
#[cfg(not(target_os = "linux"))]
mod os {
    /// Always `None`.
    pub fn map(_bytes: usize) -> Option<*mut u8> {
        None
    }

    /// Never called: nothing is mapped.
    pub fn unmap(_ptr: *mut u8, _bytes: usize) {}
}

#[cfg(test)]
mod tests {
    use super::{HUGE_PAGE, HugeArray};

    #[test]
    fn arrays_hold_their_values_and_large_ones_are_mapped_aligned() {
        let a = HugeArray::filled(200_000, 7u64);
        assert_eq!(a.len(), 200_000);
        assert!(a.iter().all(|&x| x == 7));
        if cfg!(target_os = "linux") {
            assert_eq!(a.mapped, HUGE_PAGE, "1.6 MB in one huge page");
            assert_eq!(a.as_ptr() as usize % HUGE_PAGE, 0);
        }
        let mut b = HugeArray::filled(3, [1.0f32; 5]);
        assert_eq!(b.mapped, 0, "small arrays come from the heap");
        b[2][4] = 2.0;
        assert_eq!(b[2], [1.0, 1.0, 1.0, 1.0, 2.0]);
        let empty = HugeArray::filled(0, 1u8);
        assert!(empty.is_empty());
        assert!(HugeArray::<u8>::default().is_empty());
    }
}
