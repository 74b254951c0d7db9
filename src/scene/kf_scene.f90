!> The scene: everything one case needs, with the defaults of a reference-study trefoil run.
!> One derived type per namelist group; the reader (kf_scene_read) fills and validates it.
module kf_scene
  use kf_kinds, only: wp, i8
  implicit none
  private

  integer, parameter, public :: path_len = 512
  integer, parameter, public :: name_len = 32

  !> &chain: the initial shape.
  type, public :: chain_params_t
    character(len=name_len) :: shape = 'trefoil'   !< trefoil | candycane | straight | random | file
    integer :: n_beads = 99                         !< used by straight and random (fixed for the others)
    character(len=1) :: orientation = 'a'           !< trefoil orientation a..e
    integer :: trefoil_removed_point = 100          !< which of the 100 trefoil points is removed
    real(wp) :: bond_length = 1.02_wp               !< l0, rest length of the springs
    character(len=path_len) :: coordinate_file = '' !< shape = 'file': one bead per line, x y z
    integer(i8) :: seed = 20150509_i8               !< candy-cane rotation, random chain
    real(wp) :: straight_direction(3) = [0.0_wp, 0.0_wp, 1.0_wp] !< axis of the straight chain
  end type chain_params_t

  !> &forces: which forces exist.
  type, public :: forces_params_t
    logical :: springs = .true.
    real(wp) :: spring_k = 500.0_wp                 !< per pi eta d gamma_dot
    logical :: bending = .true.
    real(wp) :: bending_a = 2.2_wp                  !< A, per pi eta d^4 gamma_dot
    logical :: excluded_volume = .false.
    real(wp) :: ev_strength = 100.0_wp              !< stiffness of the non-bonded repulsion
    real(wp) :: ev_range = 1.0_wp                   !< repulsion acts for |r_i - r_j| < ev_range
    real(wp) :: external_force(3) = 0.0_wp          !< the same force on every bead
  end type forces_params_t

  !> &flow: the ambient linear flow v0 = G r.
  type, public :: flow_params_t
    character(len=name_len) :: flow_type = 'shear'  !< shear | linear | quiescent
    real(wp) :: shear_rate = 1.0_wp                 !< shear: v0 = (shear_rate z, 0, 0)
    real(wp) :: velocity_gradient(3, 3) = 0.0_wp    !< linear: G(i,j) = d v0_i / d r_j, traceless
  end type flow_params_t

  !> &hydro: the hydrodynamic model.
  type, public :: hydro_params_t
    character(len=name_len) :: model = 'rpy'        !< none | rpy | multipole
    integer :: order = 2                            !< multipole order L
    logical :: lubrication = .true.                 !< multipole: lubrication corrections
    real(wp) :: eps_lub = -1.0_wp                   !< BWE overlap shift; < 0 means the tolerance
    character(len=name_len) :: update = 'adaptive'  !< multipole: adaptive (reuse, the default) | stage (exact every stage)
    character(len=name_len) :: overlap = 'pair'     !< multipole: pair (BWE per pair) | separate (kf_overlap_rule)
  end type hydro_params_t

  !> &integrator: time stepping.
  type, public :: integrator_params_t
    character(len=name_len) :: method = 'dopri45'   !< dopri45 (adaptive) | rk4 (fixed step)
    real(wp) :: t_end = 1000.0_wp
    real(wp) :: tolerance = 1.0e-4_wp               !< error per step on positions, units of d
    real(wp) :: dt_initial = 1.0e-3_wp
    real(wp) :: dt_min = 1.0e-9_wp                  !< below this the case fails (step underflow)
    real(wp) :: dt_max = 0.5_wp
    integer(i8) :: max_steps = 100000000_i8
  end type integrator_params_t

  !> &output: files and progress.
  type, public :: output_params_t
    character(len=path_len) :: directory = 'results'
    character(len=path_len) :: case_name = ''       !< default: derived from the parameters
    real(wp) :: frame_interval = 1.0_wp             !< simulated time between frames
    real(wp) :: progress_interval = 10.0_wp         !< wall seconds between progress lines
    logical :: diagnostics = .true.                 !< strand passages, overlaps, bond strain per step
    logical :: stresslet = .false.                  !< the fibre's stresslet and rheology per frame
  end type output_params_t

  !> The whole scene of one case.
  type, public :: scene_t
    character(len=path_len) :: source_file = ''     !< where it was read from
    type(chain_params_t) :: chain
    type(forces_params_t) :: forces
    type(flow_params_t) :: flow
    type(hydro_params_t) :: hydro
    type(integrator_params_t) :: integrator
    type(output_params_t) :: output
  end type scene_t

end module kf_scene
