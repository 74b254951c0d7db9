!> A run that starts from another run's stepper state (&chain stepper_state; the file's layout in
!> kf_stepper_state_file): the state must be of the scene's stepper and of the chain the scene
!> starts from, bead for bead and bit for bit; then the stepper takes it, its clock moved so that
!> the state's time is this run's t = 0. Used at set-up (kf_scene_run: refused before anything
!> is written) and when the case starts (kf_case_runner).
module kf_stepper_start
  use kf_kinds, only: wp
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_scene, only: scene_t
  use kf_scene_check, only: refuse, quoted
  use kf_stepper, only: stepper_t
  use kf_stepper_state_file, only: stepper_state_t, read_stepper_state
  implicit none
  private

  public :: start_from_state

contains

  !> Give `integ` (made for the scene `sc`) the state of &chain stepper_state, checked against the
  !> scene's method and the chain `r` the run starts from; nothing when stepper_state is ''.
  !> Refusals name the scene file, the variable and the file, and say what does not match.
  subroutine start_from_state(sc, r, integ, error)
    type(scene_t), intent(in) :: sc
    real(wp), intent(in) :: r(:, :)
    class(stepper_t), intent(inout) :: integ
    type(error_t), allocatable, intent(out) :: error
    type(stepper_state_t) :: st
    type(error_t), allocatable :: why
    character(len=:), allocatable :: path
    path = trim(sc%chain%stepper_state)
    if (len(path) == 0) return
    call read_stepper_state(path, st, why)
    if (.not. allocated(why)) call check_state(why)
    if (.not. allocated(why)) call integ%set_state(st%stepper%reals, st%stepper%ints, why)
    if (allocated(why)) then
      call refuse(error, trim(sc%source_file), 'chain', 'stepper_state', quoted(path), &
        "a stepper state of this scene's method at the coordinate file's positions: "//why%message)
      return
    end if
    call integ%shift_clock(-st%t)

  contains

    subroutine check_state(err)
      type(error_t), allocatable, intent(out) :: err
      if (st%stepper%name /= trim(sc%integrator%method)) then
        call fatal_error(err, "it holds the state of stepper '"//st%stepper%name//"', the scene's &integrator method is '"// &
          trim(sc%integrator%method)//"'")
      else if (size(st%r, 2) /= size(r, 2)) then
        call fatal_error(err, 'it holds '//to_str(size(st%r, 2))//' beads, the chain '//to_str(size(r, 2)))
      else if (any(st%r /= r)) then
        call fatal_error(err, 'its positions differ from the chain the scene starts from (largest difference '// &
          to_str(maxval(abs(st%r - r)), '(es10.3)')//' d)')
      end if
    end subroutine check_state

  end subroutine start_from_state

end module kf_stepper_start
