!> Near-contact forms of the 22 two-sphere resistance functions and the "exact" (converged)
!> two-sphere functions obtained by joining them to the high-order multipole solution.
!>
!> Near contact (xi = gap/radius = 2 (r/d - 1)), MULTIPOLE.md 13.1:
!>   f = g1/xi + g2 ln(1/xi) + A + g3 xi ln(1/xi) + c1 xi + c2 xi^2 ln(1/xi) + c3 xi^2,
!> g1..g3 exact (Jeffrey-Onishi 1984, Jeffrey 1992, Townsend 2023 at lambda = 1), A and c1..c3
!> fitted to converged multipole values: near_coeff holds MULTIPOLE.md table 13.1 (X^C constants
!> 7 zeta(3)/8 and -zeta(3)/8 in closed form); the forms use the generator's re-fit by default. Exact functions: this form for xi <= xi_lo, the multipole with
!> L = max(24, ceil(20/sqrt(xi))) for xi >= xi_hi, and a C2 blend in between (no jump).
module kf_near_contact
  use kf_kinds, only: wp
  use kf_error, only: error_t
  use kf_two_sphere, only: n_functions, two_sphere_resistance
  use kf_lubrication_data, only: lub_near_fit
  implicit none
  private

  public :: near_contact_form, singular_part, singular_weight, exact_resistance, exact_order
  public :: smoothstep

  !> Join window of the exact functions (in xi).
  real(wp), parameter, public :: xi_join_lo = 0.01_wp, xi_join_hi = 0.02_wp
  !> Window (in u = sqrt(xi)) over which the subtracted singular part is switched off in the
  !> tables (xi from 0.09 to 1, r from 1.045 d to 1.5 d).
  real(wp), parameter, public :: u_sing_lo = 0.3_wp, u_sing_hi = 1.0_wp

  real(wp), parameter :: zeta3 = 1.2020569031595942854_wp

  !> Coefficients (g1, g2, g3, A, c1, c2, c3) per function, order of kf_two_sphere.
  real(wp), parameter, public :: near_coeff(7, n_functions) = reshape([ &
    1.0_wp/4, 9.0_wp/40, 3.0_wp/112, 0.995359_wp, 0.1260_wp, -0.054_wp, 0.163_wp, &
    -1.0_wp/4, -9.0_wp/40, -3.0_wp/112, -0.350218_wp, -0.0679_wp, 0.054_wp, -0.168_wp, &
    0.0_wp, 1.0_wp/6, 0.0_wp, 0.998324_wp, 0.1110_wp, 0.000_wp, -0.019_wp, &
    0.0_wp, -1.0_wp/6, 0.0_wp, -0.273663_wp, -0.0248_wp, -0.000_wp, 0.004_wp, &
    0.0_wp, -1.0_wp/4, -1.0_wp/8, 0.238968_wp, -0.2895_wp, -0.001_wp, -0.008_wp, &
    0.0_wp, 1.0_wp/4, 1.0_wp/8, -0.001665_wp, 0.1385_wp, 0.001_wp, 0.052_wp, &
    0.0_wp, 0.0_wp, -1.0_wp/8, 7.0_wp*zeta3/8.0_wp, 0.0767_wp, -0.051_wp, -0.119_wp, &
    0.0_wp, 0.0_wp, 1.0_wp/8, -zeta3/8.0_wp, 0.0275_wp, 0.051_wp, 0.070_wp, &
    0.0_wp, 1.0_wp/5, 47.0_wp/250, 0.702852_wp, 0.2500_wp, 0.034_wp, 0.059_wp, &
    0.0_wp, 1.0_wp/20, 31.0_wp/500, -0.027435_wp, -0.0147_wp, 0.029_wp, 0.057_wp, &
    3.0_wp/8, 27.0_wp/80, 117.0_wp/560, -0.469277_wp, 0.3551_wp, -0.060_wp, 0.314_wp, &
    -3.0_wp/8, -27.0_wp/80, -117.0_wp/560, 0.195424_wp, -0.2867_wp, 0.060_wp, -0.310_wp, &
    0.0_wp, 1.0_wp/8, 1.0_wp/16, -0.141059_wp, 0.1565_wp, 0.000_wp, 0.001_wp, &
    0.0_wp, -1.0_wp/8, -1.0_wp/16, 0.102414_wp, -0.1144_wp, -0.000_wp, -0.019_wp, &
    0.0_wp, 1.0_wp/40, 137.0_wp/2000, -0.074073_wp, 0.0388_wp, 0.014_wp, 0.030_wp, &
    0.0_wp, 1.0_wp/10, 113.0_wp/2000, -0.029352_wp, 0.0325_wp, 0.017_wp, 0.045_wp, &
    3.0_wp/20, 27.0_wp/200, 353.0_wp/2800, 0.717323_wp, 0.1387_wp, 0.015_wp, 0.168_wp, &
    3.0_wp/20, 27.0_wp/200, 493.0_wp/2800, -0.145983_wp, 0.0619_wp, 0.019_wp, 0.205_wp, &
    0.0_wp, 3.0_wp/25, 57.0_wp/2500, 0.884519_wp, 0.1549_wp, -0.008_wp, -0.024_wp, &
    0.0_wp, 3.0_wp/100, 333.0_wp/2500, -0.207654_wp, 0.0126_wp, 0.524_wp, -1.054_wp, &
    0.0_wp, 0.0_wp, -3.0_wp/40, 1.025089_wp, 0.0574_wp, -0.019_wp, -0.095_wp, &
    0.0_wp, 0.0_wp, 3.0_wp/40, -0.072306_wp, 0.0341_wp, 0.018_wp, 0.015_wp], [7, n_functions])

contains

  !> C2 (quintic) step: 0 for u <= 0, 1 for u >= 1.
  pure real(wp) function smoothstep(u)
    real(wp), intent(in) :: u
    real(wp) :: v
    v = min(1.0_wp, max(0.0_wp, u))
    smoothstep = v*v*v*(10.0_wp - 15.0_wp*v + 6.0_wp*v*v)
  end function smoothstep

  !> The 7-term near-contact form of all 22 functions at gap xi > 0, with the constants A, c1..c3
  !> re-fitted by knotflow-lubgen (kf_lubrication_data%lub_near_fit; they agree with MULTIPOLE.md
  !> table 13.1 to 5e-6) or, when present, `fitted` (rows A, c1, c2, c3).
  pure subroutine near_contact_form(xi, f, fitted)
    real(wp), intent(in) :: xi
    real(wp), intent(out) :: f(n_functions)
    real(wp), intent(in), optional :: fitted(4, n_functions)
    real(wp) :: lg, c(4, n_functions)
    if (present(fitted)) then
      c = fitted
    else
      c = lub_near_fit
    end if
    lg = log(1.0_wp/xi)
    f = near_coeff(1, :)/xi + near_coeff(2, :)*lg + near_coeff(3, :)*xi*lg &
        + c(1, :) + c(2, :)*xi + c(3, :)*xi*xi*lg + c(4, :)*xi*xi
  end subroutine near_contact_form

  !> Singular part g1/xi + g2 ln(1/xi) + g3 xi ln(1/xi) (the terms subtracted before tabulating).
  pure subroutine singular_part(xi, f)
    real(wp), intent(in) :: xi
    real(wp), intent(out) :: f(n_functions)
    real(wp) :: lg
    lg = log(1.0_wp/xi)
    f = near_coeff(1, :)/xi + near_coeff(2, :)*lg + near_coeff(3, :)*xi*lg
  end subroutine singular_part

  !> Weight of the subtracted singular part: exactly 1 near contact, 0 beyond u_sing_hi, with an
  !> infinitely differentiable transition in u = sqrt(xi) (so the tabulated remainder is smooth
  !> on the table's grid in u).
  pure real(wp) function singular_weight(xi)
    real(wp), intent(in) :: xi
    real(wp) :: t, a, b
    t = (sqrt(xi) - u_sing_lo)/(u_sing_hi - u_sing_lo)
    if (t <= 0.0_wp) then
      singular_weight = 1.0_wp
    else if (t >= 1.0_wp) then
      singular_weight = 0.0_wp
    else
      a = exp(-1.0_wp/t)
      b = exp(-1.0_wp/(1.0_wp - t))
      singular_weight = b/(a + b)
    end if
  end function singular_weight

  !> Truncation order used for the converged multipole functions at gap xi (MULTIPOLE.md 12.2:
  !> L ~ 20/sqrt(xi) for 1e-9).
  pure integer function exact_order(xi)
    real(wp), intent(in) :: xi
    exact_order = max(24, ceiling(20.0_wp/sqrt(max(xi, 1.0e-4_wp))))
  end function exact_order

  !> Converged ("exact") two-sphere resistance functions at centre distance r (units of d, r > 1).
  !> `fitted` as in near_contact_form.
  subroutine exact_resistance(r, f, error, fitted)
    real(wp), intent(in) :: r
    real(wp), intent(out) :: f(n_functions)
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in), optional :: fitted(4, n_functions)
    real(wp) :: xi, w, fn(n_functions), fm(n_functions), rr
    xi = 2.0_wp*(r - 1.0_wp)
    f = 0.0_wp
    if (xi <= xi_join_lo) then
      call near_contact_form(max(xi, tiny(1.0_wp)), f, fitted)
      return
    end if
    rr = r
    w = smoothstep((xi - xi_join_lo)/(xi_join_hi - xi_join_lo))
    call two_sphere_resistance(rr, exact_order(xi), fm, error)
    if (allocated(error)) return
    if (w < 1.0_wp) then
      call near_contact_form(xi, fn, fitted)
      f = w*fm + (1.0_wp - w)*fn
    else
      f = fm
    end if
  end subroutine exact_resistance

end module kf_near_contact
