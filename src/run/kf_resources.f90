!> What one case needs, estimated at set-up: memory (the arrays whose size grows with the
!> number of pairs or with N^2) and the size of its case file (frames). A scene that cannot fit
!> in the machine's memory, or that would write more than `max_frames` frames, is refused before
!> anything runs, with the estimate in the message.
!>
!> Memory per case (bytes; N beads, P = N(N-1)/2 pairs, all sizes in 64-bit integers):
!> - chain, forces, the stepper's stages and work arrays: `per_bead_bytes`*N (generous);
!> - run diagnostics (`&output diagnostics`): kf_run_diagnostics' own `diagnostics_memory`
!>   (O(N): the close pairs of a chain no denser than close packing, about 2.4 KiB per bead);
!> - hydrodynamic model: what its module states (kf_hydro_factory's `hydro_memory_bytes`: 'rpy'
!>   56 bytes per pair, 'multipole' 360-1800 N^2 by update and stresslet; 'none' nothing).
!> The estimate is compared with the machine's physical memory (/proc/meminfo MemTotal; no
!> check where that cannot be read).
module kf_resources
  use kf_kinds, only: wp, i8
  use kf_platform, only: physical_memory, bytes_text
  use kf_strings, only: to_str, to_str_exact
  use kf_error, only: error_t, fatal_error
  use kf_scene, only: scene_t
  use kf_hydro_factory, only: hydro_memory_bytes
  use kf_run_diagnostics, only: diagnostics_memory
  use kf_pairs, only: pair_count
  implicit none
  private

  public :: case_resources_t, estimate_resources, check_resources, physical_memory, bytes_text

  !> Most frames one case may write (a case file of 10^6 frames of 99 beads is about 2.6 GB).
  integer(i8), parameter, public :: max_frames = 1000000_i8
  integer(i8), parameter :: per_bead_bytes = 2048_i8
  !> Bytes of one frame besides the positions (observables, integrator, diagnostics, chunk
  !> overhead): a round upper figure.
  integer(i8), parameter :: per_frame_bytes = 256_i8
  !> Bytes of one frame's stresslet (`&output stresslet`): 21 float64.
  integer(i8), parameter :: stresslet_frame_bytes = 168_i8

  !> The estimate for one case.
  type, public :: case_resources_t
    integer :: n_beads = 0
    integer(i8) :: pairs = 0              !< N(N-1)/2
    integer(i8) :: hydro_bytes = 0        !< the hydrodynamic model's arrays
    integer(i8) :: diagnostics_bytes = 0  !< the run diagnostics' arrays
    integer(i8) :: memory_bytes = 0       !< total
    integer(i8) :: frames = 0             !< frames written (t = 0 included)
    integer(i8) :: file_bytes = 0         !< size of the case file
  end type case_resources_t

contains

  !> The estimate for the scene `sc` with `n_beads` beads.
  pure function estimate_resources(sc, n_beads) result(res)
    type(scene_t), intent(in) :: sc
    integer, intent(in) :: n_beads
    type(case_resources_t) :: res
    integer(i8) :: n
    real(wp) :: frames
    n = max(0_i8, int(n_beads, i8))
    res%n_beads = n_beads
    res%pairs = pair_count(n_beads)
    res%hydro_bytes = hydro_memory_bytes(sc%hydro, n_beads, sc%output%stresslet)
    res%diagnostics_bytes = 0
    if (sc%output%diagnostics) res%diagnostics_bytes = diagnostics_memory(n_beads)
    res%memory_bytes = per_bead_bytes*n + res%hydro_bytes + res%diagnostics_bytes
    ! frames at t = 0, frame_interval, ..., and t_end (kf_case_runner); capped to stay an i8
    frames = sc%integrator%t_end/sc%output%frame_interval
    if (frames < 1.0e15_wp) then
      res%frames = ceiling(frames*(1.0_wp - 1.0e-12_wp), i8) + 1
    else
      res%frames = 10_i8**15
    end if
    res%file_bytes = res%frames*(24_i8*n + per_frame_bytes)
    ! the stresslet: two 3 x 3 tensors and three numbers per frame
    if (sc%output%stresslet) res%file_bytes = res%file_bytes + res%frames*stresslet_frame_bytes
  end function estimate_resources

  !> Refuse the scene `sc` (`n_beads` beads) when a case would not fit in `memory_limit` bytes
  !> (<= 0: no limit) or would write more than `max_frames` frames. The messages name the file,
  !> group, variable, value, the estimate and what is allowed.
  subroutine check_resources(sc, n_beads, memory_limit, error)
    type(scene_t), intent(in) :: sc
    integer, intent(in) :: n_beads
    integer(i8), intent(in) :: memory_limit
    type(error_t), allocatable, intent(out) :: error
    type(case_resources_t) :: res
    character(len=:), allocatable :: what, parts
    res = estimate_resources(sc, n_beads)
    if (res%hydro_bytes < 0) then
      call fatal_error(error, trim(sc%source_file)//': &hydro: model = '''//trim(sc%hydro%model)// &
        ''' has no memory estimate (kf_hydro_factory hydro_memory_bytes)')
      return
    end if
    if (res%frames > max_frames) then
      call fatal_error(error, trim(sc%source_file)//': &output: frame_interval = '// &
        to_str_exact(sc%output%frame_interval)//' with &integrator: t_end = '// &
        to_str_exact(sc%integrator%t_end)// &
        ' would write '//to_str(res%frames)//' frames per case (a case file of about '// &
        bytes_text(res%file_bytes)//'; allowed: at most '//to_str(max_frames)// &
        ' frames, frame_interval >= t_end/'//to_str(max_frames - 1)//')')
      return
    end if
    if (memory_limit > 0 .and. res%memory_bytes > memory_limit) then
      if (trim(sc%chain%shape) == 'file') then
        what = '&chain: coordinate_file = '''//trim(sc%chain%coordinate_file)//''' ('// &
          to_str(n_beads)//' beads)'
      else if (trim(sc%chain%shape) == 'straight' .or. trim(sc%chain%shape) == 'random') then
        what = '&chain: n_beads = '//to_str(n_beads)
      else
        what = '&chain: shape = '''//trim(sc%chain%shape)//''' ('//to_str(n_beads)//' beads)'
      end if
      parts = ''
      if (res%hydro_bytes > 0) parts = '&hydro model = '''//trim(sc%hydro%model)//''' '// &
        bytes_text(res%hydro_bytes)
      if (res%diagnostics_bytes > 0) parts = parts//merge('; ', '  ', len(parts) > 0)// &
        'run diagnostics '//bytes_text(res%diagnostics_bytes)
      call fatal_error(error, trim(sc%source_file)//': '//what//' needs about '// &
        bytes_text(res%memory_bytes)//' of memory per case ('//trim(adjustl(parts))// &
        '), more than the '//bytes_text(memory_limit)//' of this machine (allowed: a scene '// &
        'whose estimate fits; fewer beads, &output diagnostics = .false. or a lighter &hydro '// &
        'model need less)')
    end if
  end subroutine check_resources


end module kf_resources
