!> Regular and irregular solid harmonics with the normalisation of MULTIPOLE.md section 2:
!>   R_n^m = r^n P_n^m(cos theta) e^{i m phi} / (n+m)!,
!>   I_n^m = (n-m)! P_n^m(cos theta) e^{i m phi} / r^(n+1),
!> Condon-Shortley phase included, evaluated by Cartesian recurrences (no trigonometry).
!> Negative orders follow from X_n^{-m} = (-1)^m conj(X_n^m).
module kf_solid_harmonics
  use kf_kinds, only: wp
  implicit none
  private

  public :: regular_harmonics, irregular_harmonics, irregular_harmonics_real

contains

  !> Regular solid harmonics rh(n, m) = R_n^m(r) for 0 <= n <= nmax, |m| <= n
  !> (entries with |m| > n are set to zero).
  pure subroutine regular_harmonics(r, nmax, rh)
    real(wp), intent(in) :: r(3)
    integer, intent(in) :: nmax
    complex(wp), intent(out) :: rh(0:nmax, -nmax:nmax)
    complex(wp) :: xp
    real(wp) :: z, r2
    integer :: n, m

    rh = (0.0_wp, 0.0_wp)
    xp = cmplx(r(1), r(2), kind=wp)
    z = r(3)
    r2 = sum(r**2)
    rh(0, 0) = (1.0_wp, 0.0_wp)
    do m = 1, nmax   ! the diagonal first: each column below starts from it
      rh(m, m) = -xp/real(2*m, wp)*rh(m - 1, m - 1)
    end do
    do m = 0, nmax
      do n = m + 1, nmax
        if (n - 2 >= m) then
          rh(n, m) = (real(2*n - 1, wp)*z*rh(n - 1, m) - r2*rh(n - 2, m))/real(n*n - m*m, wp)
        else
          rh(n, m) = real(2*n - 1, wp)*z*rh(n - 1, m)/real(n*n - m*m, wp)
        end if
      end do
    end do
    call fill_negative(nmax, rh)
  end subroutine regular_harmonics

  !> Irregular solid harmonics ih(n, m) = I_n^m(r) for 0 <= n <= nmax, |m| <= n (r /= 0).
  pure subroutine irregular_harmonics(r, nmax, ih)
    real(wp), intent(in) :: r(3)
    integer, intent(in) :: nmax
    complex(wp), intent(out) :: ih(0:nmax, -nmax:nmax)
    complex(wp) :: xp
    real(wp) :: z, r2, rinv2
    integer :: n, m

    ih = (0.0_wp, 0.0_wp)
    xp = cmplx(r(1), r(2), kind=wp)
    z = r(3)
    r2 = sum(r**2)
    rinv2 = 1.0_wp/r2
    ih(0, 0) = cmplx(1.0_wp/sqrt(r2), 0.0_wp, kind=wp)
    do m = 1, nmax   ! the diagonal first: each column below starts from it
      ih(m, m) = -real(2*m - 1, wp)*xp*rinv2*ih(m - 1, m - 1)
    end do
    do m = 0, nmax
      do n = m + 1, nmax
        if (n - 2 >= m) then
          ih(n, m) = (real(2*n - 1, wp)*z*ih(n - 1, m) &
                      - real((n - 1)**2 - m*m, wp)*ih(n - 2, m))*rinv2
        else
          ih(n, m) = real(2*n - 1, wp)*z*ih(n - 1, m)*rinv2
        end if
      end do
    end do
    call fill_negative(nmax, ih)
  end subroutine irregular_harmonics

  !> The irregular solid harmonics of non-negative order in real arithmetic, packed, for nd
  !> points r(:, i) at once: y(i, 2 k + 1) = Re I_n^m(r(:, i)), y(i, 2 k + 2) = Im I_n^m(r(:, i))
  !> with k = n(n+1)/2 + m, 0 <= m <= n <= nmax (r /= 0). The same recurrences as
  !> `irregular_harmonics`, without the complex array, its zero fill and the negative orders;
  !> the loops over the points are innermost (they vectorise).
  pure subroutine irregular_harmonics_real(nd, r, nmax, y)
    integer, intent(in) :: nd, nmax
    real(wp), intent(in) :: r(3, nd)
    real(wp), intent(out) :: y(nd, (nmax + 1)*(nmax + 2))
    real(wp) :: rinv2(nd), t1, t2, c, w
    integer :: n, m, k, k1, k2, i

    do i = 1, nd
      rinv2(i) = 1.0_wp/sum(r(:, i)**2)
      y(i, 1) = 1.0_wp/sqrt(sum(r(:, i)**2))
      y(i, 2) = 0.0_wp
    end do
    do m = 1, nmax   ! the diagonal: I_m^m = -(2m-1) (x + iy)/r^2 I_{m-1}^{m-1}
      k = 2*(m*(m + 1)/2 + m) + 1
      k1 = 2*((m - 1)*m/2 + m - 1) + 1
      do i = 1, nd
        t1 = -real(2*m - 1, wp)*r(1, i)*rinv2(i)
        t2 = -real(2*m - 1, wp)*r(2, i)*rinv2(i)
        y(i, k) = t1*y(i, k1) - t2*y(i, k1 + 1)
        y(i, k + 1) = t1*y(i, k1 + 1) + t2*y(i, k1)
      end do
    end do
    do n = 1, nmax   ! down each column: n from m + 1
      do m = 0, n - 1
        k = 2*(n*(n + 1)/2 + m) + 1
        k1 = 2*((n - 1)*n/2 + m) + 1
        if (n - 2 >= m) then
          k2 = 2*((n - 2)*(n - 1)/2 + m) + 1
          w = real((n - 1)**2 - m*m, wp)
          do i = 1, nd
            c = real(2*n - 1, wp)*r(3, i)
            y(i, k) = (c*y(i, k1) - w*y(i, k2))*rinv2(i)
            y(i, k + 1) = (c*y(i, k1 + 1) - w*y(i, k2 + 1))*rinv2(i)
          end do
        else
          do i = 1, nd
            c = real(2*n - 1, wp)*r(3, i)
            y(i, k) = c*y(i, k1)*rinv2(i)
            y(i, k + 1) = c*y(i, k1 + 1)*rinv2(i)
          end do
        end if
      end do
    end do
  end subroutine irregular_harmonics_real

  !> X_n^{-m} = (-1)^m conj(X_n^m).
  pure subroutine fill_negative(nmax, h)
    integer, intent(in) :: nmax
    complex(wp), intent(inout) :: h(0:nmax, -nmax:nmax)
    integer :: n, m
    do n = 1, nmax
      do m = 1, n
        h(n, -m) = real((-1)**m, wp)*conjg(h(n, m))
      end do
    end do
  end subroutine fill_negative

end module kf_solid_harmonics
