!> Power spectra of observables sampled at a uniform frame interval: R_g(t), the unwrapped phi(t)
!> (linear trend removed, so that steady rolling does not swamp the spectrum) and the end-to-end
!> vector (sum of the powers of its three components). With FFTW (KNOTFLOW_HAVE_FFTW) the
!> transforms are real-to-complex (r2c); without, a direct DFT gives the same numbers.
!> power(k) = |X_k|^2 / n of the series with its mean removed, at frequency k / (n dt),
!> k = 0..n/2; the dominant period is 1/frequency of the largest power with k >= 1.
module kf_spectra
  use, intrinsic :: iso_c_binding
  use kf_kinds, only: wp
  use kf_constants, only: two_pi
  use kf_error, only: error_t, fatal_error
  implicit none
  private

#ifdef KNOTFLOW_HAVE_FFTW
  include 'fftw3.f03'
#endif

  public :: power_spectrum, dominant_period, unwrap_phase, detrend

contains

  !> Frequencies (n/2+1) and power of x sampled every dt (mean removed first).
  subroutine power_spectrum(x, dt, freq, power, error)
    real(wp), intent(in) :: x(:)
    real(wp), intent(in) :: dt
    real(wp), allocatable, intent(out) :: freq(:), power(:)
    type(error_t), allocatable, intent(out) :: error
    integer :: n, k
    real(c_double), allocatable :: xin(:)
    complex(c_double_complex), allocatable :: xout(:)
#ifdef KNOTFLOW_HAVE_FFTW
    type(c_ptr) :: plan
#else
    integer :: j
#endif
    n = size(x)
    if (n < 4) then
      call fatal_error(error, 'spectra: at least 4 frames are needed')
      return
    end if
    if (.not. (dt > 0.0_wp)) then
      call fatal_error(error, 'spectra: the frame interval must be positive')
      return
    end if
    allocate (xin(n), xout(n/2 + 1), freq(n/2 + 1), power(n/2 + 1))
    xin = x - sum(x)/n
#ifdef KNOTFLOW_HAVE_FFTW
    plan = fftw_plan_dft_r2c_1d(int(n, c_int), xin, xout, FFTW_ESTIMATE)
    if (.not. c_associated(plan)) then
      call fatal_error(error, 'spectra: FFTW could not create a plan')
      return
    end if
    xin = x - sum(x)/n                ! FFTW_ESTIMATE keeps the input, but be safe
    call fftw_execute_dft_r2c(plan, xin, xout)
    call fftw_destroy_plan(plan)
#else
    do k = 0, n/2
      xout(k + 1) = (0.0_wp, 0.0_wp)
      do j = 0, n - 1
        xout(k + 1) = xout(k + 1) + xin(j + 1)*exp(cmplx(0.0_wp, -two_pi*k*j/n, wp))
      end do
    end do
#endif
    do k = 0, n/2
      freq(k + 1) = real(k, wp)/(n*dt)
      power(k + 1) = abs(xout(k + 1))**2/n
    end do
  end subroutine power_spectrum

  !> Period 1/f of the largest power at a non-zero frequency (0 when there is no power).
  pure real(wp) function dominant_period(freq, power) result(period)
    real(wp), intent(in) :: freq(:), power(:)
    integer :: k
    period = 0.0_wp
    if (size(power) < 2) return
    k = maxloc(power(2:), 1) + 1
    if (power(k) > 0.0_wp) period = 1.0_wp/freq(k)
  end function dominant_period

  !> Remove jumps larger than pi (an angle series made continuous).
  pure function unwrap_phase(phi) result(u)
    real(wp), intent(in) :: phi(:)
    real(wp) :: u(size(phi))
    real(wp) :: d
    integer :: k
    if (size(phi) == 0) return
    u(1) = phi(1)
    do k = 2, size(phi)
      d = phi(k) - phi(k - 1)
      d = d - two_pi*anint(d/two_pi)
      u(k) = u(k - 1) + d
    end do
  end function unwrap_phase

  !> x minus its least-squares straight line in the sample index.
  pure function detrend(x) result(y)
    real(wp), intent(in) :: x(:)
    real(wp) :: y(size(x))
    real(wp) :: tm, xm, stt, stx
    integer :: n, k
    n = size(x)
    if (n < 2) then
      y = 0.0_wp
      return
    end if
    tm = 0.5_wp*(n - 1)
    xm = sum(x)/n
    stt = 0.0_wp
    stx = 0.0_wp
    do k = 1, n
      stt = stt + (k - 1 - tm)**2
      stx = stx + (k - 1 - tm)*(x(k) - xm)
    end do
    do k = 1, n
      y(k) = x(k) - xm - stx/stt*(k - 1 - tm)
    end do
  end function detrend

end module kf_spectra
