!> Heap tuning for allocation-heavy loops, called once by programs at start-up.
!> glibc hands freed memory at the top of the heap back to the system as soon as more than
!> M_TRIM_THRESHOLD (128 KiB) is free there, and takes it back with brk() on the next allocation.
!> A loop that allocates and frees a few hundred KiB per iteration (the Alexander matrices of the
!> knot analysis) then spends most of its time in system calls: the knot matrix of an N = 152 coil
!> made 100,426 brk() calls and took 7.8 s of system time for 3.2 s of user time.
module kf_memory
#ifdef KNOTFLOW_HAVE_MALLOPT
  use, intrinsic :: iso_c_binding, only: c_int
#endif
  implicit none
  private

  public :: keep_freed_heap

contains

  !> Ask the C library to keep freed heap memory (up to 256 MiB) for reuse instead of returning it
  !> at once, and to serve blocks up to 32 MiB from the heap. Does nothing where the C library has no mallopt.
  subroutine keep_freed_heap()
#ifdef KNOTFLOW_HAVE_MALLOPT
    interface
      integer(c_int) function mallopt(param, value) bind(c, name='mallopt')
        import :: c_int
        integer(c_int), value :: param, value
      end function mallopt
    end interface
    integer(c_int), parameter :: m_trim_threshold = -1_c_int, m_top_pad = -2_c_int, &
                                  m_mmap_threshold = -3_c_int
    integer(c_int) :: ignored
    ignored = mallopt(m_trim_threshold, 268435456_c_int)
    ignored = mallopt(m_top_pad, 16777216_c_int)
    ! Fixing the trim threshold also fixes the mmap threshold (128 KiB), so that every larger
    ! block (the multipole matrices) would be mapped and unmapped at each use: raise it to the
    ! largest value glibc accepts on 64-bit systems (32 MiB).
    ignored = mallopt(m_mmap_threshold, 33554432_c_int)
#endif
  end subroutine keep_freed_heap

end module kf_memory
