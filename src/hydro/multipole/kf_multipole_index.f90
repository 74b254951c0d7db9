!> Where the unknowns of the N-sphere multipole system (kf_multipole_system) sit in its global
!> arrays, so that no other code does index arithmetic on them.
!>
!> Per sphere the unknowns are grouped (kf_multipole_blocks `grp`) into runs of the local index
!> g = 1..3h (h = L(L+2)): 1 phi n >= 2 [1, h-3], 2 chi n >= 2 [h-2, 2h-6], 3 phi n = 1
!> [2h-5, 2h-3], 4 chi n = 1 [2h-2, 2h], 5 p [2h+1, 3h]; the phi n = 2 moments q = 0..4 open
!> run 1. Global order of K (the p-moments eliminated): run 1 of every sphere, then run 2, 3, 4
!> of every sphere; the last 6N rows (runs 3 and 4: force and torque moments) are the set P.
!> Rows of B (the phi <- p couplings): run 1 of every sphere, then run 3; columns: the p
!> unknowns sphere by sphere.
module kf_multipole_index
  implicit none
  private

  !> Index map of the system for h unknowns per family and sphere and n spheres.
  type, public :: multipole_index_t
    integer :: h = 0                        !< L(L+2)
    integer :: n = 0                        !< spheres
    integer :: lo(5) = 0, hi(5) = 0         !< the local runs
    integer :: kmap(3) = [2, 3, 1]          !< P component (real q 0..2) of Cartesian x, y, z
  contains
    procedure :: init
    procedure :: nr, nqt, n6, b_rows, b_run_rows, p_unknowns
    procedure :: k_start, k_row, b_start, b_row, p_start, p_index, strain_row
  end type multipole_index_t

contains

  !> The map for h = L(L+2) unknowns per family and sphere and n spheres.
  pure subroutine init(this, h, n)
    class(multipole_index_t), intent(inout) :: this
    integer, intent(in) :: h, n
    this%h = h
    this%n = n
    this%lo = [1, h - 2, 2*h - 5, 2*h - 2, 2*h + 1]
    this%hi = [h - 3, 2*h - 6, 2*h - 3, 2*h, 3*h]
  end subroutine init

  !> Size of K (phi and chi unknowns of every sphere).
  pure integer function nr(this)
    class(multipole_index_t), intent(in) :: this
    nr = 2*this%h*this%n
  end function nr

  !> Unknowns of K outside P (they come first).
  pure integer function nqt(this)
    class(multipole_index_t), intent(in) :: this
    nqt = 2*(this%h - 3)*this%n
  end function nqt

  !> Size of P: 6N.
  pure integer function n6(this)
    class(multipole_index_t), intent(in) :: this
    n6 = 6*this%n
  end function n6

  !> Rows of B (the phi unknowns of runs 1 and 3 of every sphere): h N.
  pure integer function b_rows(this)
    class(multipole_index_t), intent(in) :: this
    b_rows = this%h*this%n
  end function b_rows

  !> Rows of B of the phi run `run` (1: n >= 2, (h - 3) N; 3: n = 1, 3N); they start at
  !> b_start(run, 1).
  pure integer function b_run_rows(this, run) result(m)
    class(multipole_index_t), intent(in) :: this
    integer, intent(in) :: run
    if (run == 1) then
      m = (this%h - 3)*this%n
    else
      m = 3*this%n
    end if
  end function b_run_rows

  !> Columns of B: the p unknowns of every sphere, h N.
  pure integer function p_unknowns(this)
    class(multipole_index_t), intent(in) :: this
    p_unknowns = this%h*this%n
  end function p_unknowns

  !> First row of K of run `run` (1..4) of sphere s.
  pure integer function k_start(this, run, s) result(k)
    class(multipole_index_t), intent(in) :: this
    integer, intent(in) :: run, s
    select case (run)
    case (1)
      k = (this%h - 3)*(s - 1) + 1
    case (2)
      k = (this%h - 3)*this%n + (this%h - 3)*(s - 1) + 1
    case (3)
      k = 2*(this%h - 3)*this%n + 3*(s - 1) + 1
    case default
      k = 2*(this%h - 3)*this%n + 3*this%n + 3*(s - 1) + 1
    end select
  end function k_start

  !> Row of K of the local grouped index g (1..2h) of sphere s.
  pure integer function k_row(this, g, s) result(k)
    class(multipole_index_t), intent(in) :: this
    integer, intent(in) :: g, s
    integer :: run
    do run = 4, 1, -1
      if (g >= this%lo(run)) exit
    end do
    k = this%k_start(run, s) + g - this%lo(run)
  end function k_row

  !> First row of B of the phi run `run` (1 or 3) of sphere s.
  pure integer function b_start(this, run, s) result(b)
    class(multipole_index_t), intent(in) :: this
    integer, intent(in) :: run, s
    if (run == 1) then
      b = (this%h - 3)*(s - 1) + 1
    else
      b = (this%h - 3)*this%n + 3*(s - 1) + 1
    end if
  end function b_start

  !> Row of B of the local grouped phi index g of sphere s.
  pure integer function b_row(this, g, s) result(b)
    class(multipole_index_t), intent(in) :: this
    integer, intent(in) :: g, s
    if (g >= this%lo(3)) then
      b = this%b_start(3, s) + g - this%lo(3)
    else
      b = this%b_start(1, s) + g - this%lo(1)
    end if
  end function b_row

  !> First column of B (the p unknowns) of sphere s.
  pure integer function p_start(this, s) result(p)
    class(multipole_index_t), intent(in) :: this
    integer, intent(in) :: s
    p = this%h*(s - 1) + 1
  end function p_start

  !> Index in P (1..6N) of Cartesian component c (1..3 force, 4..6 torque) of sphere i.
  pure integer function p_index(this, i, c) result(p)
    class(multipole_index_t), intent(in) :: this
    integer, intent(in) :: i, c
    if (c <= 3) then
      p = 3*(i - 1) + this%kmap(c)
    else
      p = 3*this%n + 3*(i - 1) + this%kmap(c - 3)
    end if
  end function p_index

  !> Row of K of the phi n = 2 moment q (0..4) of sphere i (the strain couples to these).
  pure integer function strain_row(this, i, q) result(k)
    class(multipole_index_t), intent(in) :: this
    integer, intent(in) :: i, q
    k = this%k_start(1, i) + q
  end function strain_row

end module kf_multipole_index
