!> Running one case: initial chain (or the checkpoint of an interrupted run), the time loop with
!> frames, checkpoints and progress reports, and the final status in the case file.
!> The library never prints: progress lines go to a reporter (case_reporter_t) the program supplies.
module kf_case_runner
  use, intrinsic :: iso_fortran_env, only: int64
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str, to_str_short, to_str_exact
  use kf_error, only: error_t, fatal_error
  use kf_scene, only: scene_t
  use kf_scene_items, only: scene_items, scene_text
  use kf_scene_item, only: scene_item_t, item_string, item_integer, item_real, item_logical, item_real_array
  use kf_chain_shapes, only: build_initial_chain
  use kf_stepper_start, only: start_from_state
  use kf_dynamics, only: dynamics_t
  use kf_hydro_model, only: hydro_stats_t
  use kf_stepper, only: stepper_t
  use kf_stepper_factory, only: make_stepper
  use kf_case_file, only: case_file_t
  use kf_case_frames, only: frame_t, frame_template
  use kf_case_checkpoint, only: stepper_checkpoint_t
  use kf_case_runs, only: run_record_t
  use kf_case_verify, only: case_file_status, verify_case_file, read_frames
  use kf_run_segment, only: run_segment_t, run_launch_t
  use kf_frame_records, only: fill_frame
  use kf_run_diagnostics, only: run_diagnostics_t, diag_pair_cutoff
  use kf_fs, only: remove_file, move_aside, file_exists, file_in_use, file_not_writable
  use kf_file_type, only: is_symbolic_link
  use kf_case_match, only: check_reusable
  use kf_h5, only: h5_extend_truncated, h5_raise_end
  use kf_signals, only: stop_signal, signal_name
  implicit none
  private

  !> Outcomes of a case; case_stopped: a stop signal (kf_signals) ended it after a whole frame.
  integer, parameter, public :: case_ok = 0, case_failed = 1, case_skipped = 2, case_stopped = 3
  !> Their names, indexed by the outcome (the C interface's case statuses).
  character(len=8), parameter, public :: case_outcome_names(0:3) = &
    [character(len=8) :: 'finished', 'failed', 'skipped', 'stopped']
  !> The status while the phases of run_case go on (never returned).
  integer, parameter :: case_undecided = -1

  !> Receives the progress lines of a case (an object, not a procedure argument: the program's
  !> reporter carries its state, e.g. the rank, without an internal procedure and its trampoline).
  type, abstract, public :: case_reporter_t
  contains
    procedure(report_line_i), deferred :: line
  end type case_reporter_t

  abstract interface
    !> Receives one progress line.
    subroutine report_line_i(this, line)
      import :: case_reporter_t
      class(case_reporter_t), intent(inout) :: this
      character(len=*), intent(in) :: line
    end subroutine report_line_i
  end interface

  public :: run_case, case_path

  !> Root attributes of the hydrodynamic model's counters, in the order of hydro_stats_t.
  character(len=*), parameter :: hydro_counters(4) = [character(len=20) :: 'hydro.evaluations', &
    'hydro.refreshes', 'hydro.reused', 'hydro.cg_iterations']

contains

  !> The case file of a scene: <output.directory>/<output.case_name>.h5
  function case_path(sc) result(path)
    type(scene_t), intent(in) :: sc
    character(len=:), allocatable :: path
    path = trim(sc%output%directory)//'/'//trim(sc%output%case_name)//'.h5'
  end function case_path

  !> Run (or resume, or skip) the case described by `sc`. Returns case_ok, case_failed or
  !> case_skipped and a one-line message. Failures are recorded in the case file's status.
  !> `launch` (MPI ranks, BLAS threads) goes into the /runs entry of this run segment.
  !> In six named phases (contained procedures sharing the case's state below): the file's state,
  !> start or resume, the parts, the file, the frame loop, the end. A phase that decides the case
  !> (skipped, failed, stopped) sets `status`, and the phases after it do not run.
  subroutine run_case(sc, report, status, message, launch)
    type(scene_t), intent(in) :: sc
    class(case_reporter_t), intent(inout) :: report
    integer, intent(out) :: status
    character(len=:), allocatable, intent(out) :: message
    type(run_launch_t), intent(in) :: launch
    type(error_t), allocatable :: error
    type(case_file_t) :: file
    type(dynamics_t), target :: dyn
    class(stepper_t), allocatable :: integ
    type(stepper_checkpoint_t) :: saved
    integer(i8) :: hydro_base(4)   !< hydro counters of the run before a resume
    integer(i8), allocatable :: saved_counters(:)
    type(run_diagnostics_t), allocatable :: diag   !< allocated only with diagnostics: else absent
    type(frame_t) :: frame   !< the record of the frame written last (its parts: those of the file)
    type(run_segment_t) :: segment
    type(run_record_t) :: final   !< the segment's record at the end
    real(wp), allocatable :: r(:, :)
    real(wp) :: rotation(3, 3), t, t_next, dt
    integer(i8) :: steps, rejected, nframes
    character(len=:), allocatable :: path, state, name, moved_to
    integer(int64) :: clock0, clock_last, clock_now, rate
    real(wp) :: t_start
    logical :: resumed, with_diag, with_stresslet, unreadable, damaged, extended
    integer(i8) :: old_size, new_size

    call segment%begin(launch)
    path = case_path(sc)
    name = trim(sc%output%case_name)
    hydro_base = 0
    status = case_undecided
    ! each phase either leaves the case undecided, for the next one, or decides it (status set)
    call check_file()
    if (status == case_undecided) call choose_start()
    if (status == case_undecided) call build_parts()
    if (status == case_undecided) call start_file()
    if (status == case_undecided) call frame_loop()
    if (status == case_undecided) call finish_case()

  contains

    !> Phase 1, the file's state: a link, a file in use or not writable refuses the case; a file
    !> cut short by a failed write is extended, one killed while writing has its end raised; `state`
    !> is then 'missing', 'running', 'finished', 'failed: ...' or 'corrupt: ...'.
    subroutine check_file()
      ! knotflow writes its case files itself, never through a link planted at their name
      if (is_symbolic_link(path)) then
        status = case_failed
        message = 'case file '//path//' not used: it is a symbolic link (knotflow never writes through one): '// &
          'remove the link, or put the file itself there; nothing was changed'
        return
      end if
      ! A file another process holds for writing cannot even be read: say so rather than call it
      ! damaged.
      if (refused_access(.false.)) return
      call case_file_status(path, state, error)
      if (allocated(error)) then
        status = case_failed
        message = error%message
        return
      end if
      ! Anything but skipping a finished file writes to it or moves it: a file in use by another
      ! process or not writable for this one fails the case (nothing moved, nothing recomputed).
      if (state /= 'missing' .and. state /= 'finished') then
        if (refused_access(.true.)) return
      end if
      resumed = .false.
      with_diag = sc%output%diagnostics
      with_stresslet = sc%output%stresslet
      if (index(state, 'corrupt: ') == 1) then
        ! A file cut short by a failed write (full disk) cannot be opened until it has its
        ! recorded size again; its checkpoint is then checked like any other.
        call h5_extend_truncated(path, extended, old_size, new_size, error)
        if (allocated(error)) deallocate (error)
        if (extended) then
          call report%line('case '//name//': '//path//' was cut short by a failed write ('//to_str(old_size)//' of '// &
                      to_str(new_size)//' bytes): extended to its recorded size to read its checkpoint')
          call case_file_status(path, state, error)
          if (allocated(error)) then
            status = case_failed
            message = error%message
            return
          end if
        end if
      end if
      if (state == 'running') then
        ! A kill while HDF5 flushed may have left objects written beyond the end the superblock
        ! records: the end is raised to include them before the file is opened.
        call h5_raise_end(path, extended, old_size, new_size, error)
        if (allocated(error)) then
          status = case_failed
          message = error%message
          return
        end if
        if (extended) call report%line('case '//name//': '//path//' holds '//to_str(new_size - old_size)// &
          ' bytes written after the end its superblock records (killed while writing): end raised to '// &
          to_str(new_size)//' bytes')
      end if
    end subroutine check_file

    !> Phase 2, start or resume: a finished file that matches the scene and reads back whole is
    !> skipped; a running one that matches is opened for the resume when its kept frames and its
    !> checkpoint are good; a damaged one is moved aside, a failed one removed (computed again).
    subroutine choose_start()
      if (state == 'finished' .or. state == 'running') then
        ! Reused only when the stored scene is the requested one (knotflow checks every case at
        ! set-up already; this guards other callers).
        call check_reusable(path, sc, error, unreadable)
        if (allocated(error)) then
          status = case_failed
          message = error%message
          return
        end if
        if (unreadable) state = 'corrupt: its scene attributes cannot be read'
      end if
      if (state == 'finished') then
        ! A finished file is skipped only when it reads back completely (checksums included).
        call verify_case_file(path, sc%integrator%t_end, error)
        if (.not. allocated(error)) then
          status = case_skipped
          message = 'already finished ('//path//')'
          return
        end if
        state = 'corrupt: marked finished, but '//error%message
        deallocate (error)
      end if
      if (state == 'running') then
        ! The frames a resume keeps are checked first (finite times and coordinates, times that
        ! increase): a bad early frame is found now, not after the whole remaining run.
        block
          real(wp), allocatable :: kept_t(:), kept_r(:, :, :)
          call read_frames(path, kept_t, kept_r, error)
        end block
        if (allocated(error)) then
          state = 'corrupt: a frame it keeps is bad: '//error%message
          deallocate (error)
        end if
      end if
      if (state == 'running') then
        call file%open_resume(path, r, t, dt, steps, rejected, nframes, error, saved, saved_counters)
        if (.not. allocated(error)) then
          resumed = .true.
          ! a file written before the run diagnostics existed is continued without them
          with_diag = with_diag .and. file%has_diagnostics()
          ! (the scene match guarantees that a file asked for the stresslet was written with it)
          with_stresslet = with_stresslet .and. file%has_stresslet()
        else
          state = 'corrupt: its checkpoint cannot be resumed: '//error%message
          deallocate (error)
        end if
      end if
      if (index(state, 'corrupt: ') == 1) then
        ! (a finished file found damaged: not yet checked for writing)
        if (refused_access(.true.)) return
        ! Damaged or unreadable: moved aside (never deleted) and the case recomputed.
        call move_aside(path, moved_to, error)
        if (allocated(error)) then
          status = case_failed
          message = path//' is damaged ('//state(10:)//') and cannot be moved aside: '//error%message
          return
        end if
        call report%line('case '//name//': '//path//' is damaged ('//state(10:)//'): moved to '//moved_to// &
                    '; computing the case again')
      else if (state /= 'missing' .and. .not. resumed) then
        ! Failed cases are recomputed from scratch.
        call remove_file(path)
      end if
    end subroutine choose_start

    !> Phase 3, the parts: the initial chain (unless resumed), the dynamics, the stepper (its state
    !> from the checkpoint when resumed, else from &chain stepper_state when the scene names one),
    !> the run diagnostics and the stresslet when asked for.
    subroutine build_parts()
      if (.not. resumed) then
        call build_initial_chain(sc%chain, r, rotation, error)
        if (allocated(error)) then
          status = case_failed
          message = error%message
          return
        end if
      end if
      call dyn%init(sc, size(r, 2), error)
      if (.not. allocated(error)) call make_stepper(sc%integrator, integ, error)
      if (.not. allocated(error) .and. resumed) call restore_stepper(error)
      if (.not. allocated(error) .and. .not. resumed) call start_from_state(sc, r, integ, error)
      if (allocated(error)) then
        if (resumed) call file%close()
        status = case_failed
        message = error%message
        return
      end if

      if (with_diag) then
        allocate (diag)
        call diag%init(size(r, 2), sc%chain%bond_length)
        ! one pair list per configuration: the dynamics' list also serves the diagnostics
        call dyn%need_pairs(diag_pair_cutoff)
        call diag%share_pairs(dyn%pairs)
      end if
      frame = frame_template(size(r, 2), with_diag, with_stresslet)
      if (resumed) then
        if (with_diag) call restore_diagnostics(error)
        if (.not. allocated(error)) call read_hydro_counters(error)
        if (allocated(error)) then
          call file%close()
          status = case_failed
          message = error%message
          return
        end if
      end if
    end subroutine build_parts

    !> Phase 4, the file: a new /runs entry in the resumed file, or a new file with its attributes,
    !> groups and the first frame (t = 0).
    subroutine start_file()
      saved%name = trim(sc%integrator%method)
      if (resumed) then
        call report%line('case '//name//': resuming at t = '//to_str_short(t)//' from its checkpoint ('// &
                    to_str(nframes)//' frames)')
        call segment%place(t, integ%steps())
        call file%start_run(segment%record(t, integ%steps()), error)
        if (allocated(error)) then
          call write_failed(error%message)
          return
        end if
      else
        call file%create(path, name, size(r, 2), scene_text(sc), rotation, error)
        if (.not. allocated(error)) call write_scene_attributes(file, sc, error)
        if (.not. allocated(error) .and. with_diag) call file%enable_diagnostics(error)
        if (.not. allocated(error) .and. with_stresslet) call file%enable_stresslet(error)
        ! every root attribute rewritten with the frames exists before the first frame, so that
        ! later frames overwrite them in place
        if (.not. allocated(error)) call write_hydro_counters(error)
        if (.not. allocated(error)) call file%start_run(segment%record(0.0_wp, 0_i8), error)
        if (allocated(error)) then
          call write_failed(error%message)
          return
        end if
        t = 0.0_wp
        nframes = 0
        if (with_diag) call diag%start(t, r)
        call record_frame()
        if (.not. allocated(error)) then
          call integ%get_state(saved%reals, saved%ints)
          call file%append_frame(frame, error, saved, hydro_counts(), segment%record(t, 0_i8))
          if (allocated(error)) then
            call write_failed(error%message)
            return
          end if
        end if
        if (allocated(error)) then
          call fail(error%message)
          return
        end if
        nframes = 1
      end if
    end subroutine start_file

    !> Phase 5, the frame loop: advance to the next frame time, append the frame and its checkpoint,
    !> stop after a whole frame on a stop signal, report progress every progress_interval.
    subroutine frame_loop()
      call system_clock(clock0, rate)
      clock_last = clock0
      t_start = t
      do while (t < sc%integrator%t_end*(1.0_wp - 1.0e-12_wp))
        t_next = min(sc%integrator%t_end, real(nframes, wp)*sc%output%frame_interval)
        if (t_next <= t) t_next = min(sc%integrator%t_end, t + sc%output%frame_interval)
        call integ%advance(dyn, t, r, t_next, error, diag)
        if (allocated(error)) then
          call fail(error%message)
          return
        end if
        call record_frame()
        if (allocated(error)) then
          call fail(error%message)
          return
        end if
        call integ%get_state(saved%reals, saved%ints)
        call segment%sample_load()
        call file%append_frame(frame, error, saved, hydro_counts(), segment%record(t, integ%steps()))
        if (.not. allocated(error)) call write_hydro_counters(error)
        if (allocated(error)) then
          call write_failed(error%message)
          return
        end if
        nframes = nframes + 1
        if (stop_signal() /= 0 .and. t < sc%integrator%t_end*(1.0_wp - 1.0e-12_wp)) then
          ! SIGTERM or SIGINT: the frame and its checkpoint are written; stop here
          call stopped()
          return
        end if
        call system_clock(clock_now)
        if (real(clock_now - clock_last, wp)/rate >= sc%output%progress_interval) then
          clock_last = clock_now
          call report%line(progress_line())
        end if
      end do
    end subroutine frame_loop

    !> Phase 6, the end: the file read back, verified and marked finished (a damaged one moved
    !> aside), and the case's one-line summary.
    subroutine finish_case()
      ! 'finished' only after the last frame is flushed and the file read back and verified.
      final = segment%record(t, integ%steps())
      call file%finish(sc%integrator%t_end, error, damaged, final)
      if (allocated(error)) then
        status = case_failed
        if (damaged) then
          message = error%message
          call move_aside(path, moved_to, error)
          if (allocated(error)) then
            message = message//'; it cannot be moved aside: '//error%message
          else
            message = message//'; moved to '//moved_to//', the next run computes the case again'
          end if
        else
          call write_failed(error%message)
        end if
        return
      end if
      status = case_ok
      call system_clock(clock_now)
      message = to_str(integ%steps())//' steps ('//to_str(integ%rejected())//' rejected), '// &
                to_str_short(real(clock_now - clock0, wp)/rate)//' s'
      if (ieee_is_finite(final%load_mean)) message = message//', mean load '//to_str_short(final%load_mean)
    end subroutine finish_case

    !> Whether the existing case file cannot be used as this run needs (for writing, or only for
    !> reading): in use by another process (HDF5's file lock, kf_fs: file_in_use) or, for
    !> writing, not writable for this process. Then the case fails with the reason, and the
    !> file is left exactly as it is.
    logical function refused_access(for_writing) result(refused)
      logical, intent(in) :: for_writing
      character(len=:), allocatable :: reason
      refused = .false.
      if (.not. file_exists(path)) return
      reason = ''
      if (file_in_use(path, for_writing)) then
        reason = 'it is open in another process, which holds its HDF5 file lock (a viewer such as h5py, '// &
          'HDFView or ParaView, or another run): close it there and run again'
      else if (for_writing) then
        reason = file_not_writable(path)
        if (len(reason) > 0) reason = 'it cannot be written ('//reason//'): give it write permission (chmod u+w) '// &
          'and run again'
      end if
      if (len(reason) == 0) return
      refused = .true.
      status = case_failed
      message = 'case file '//path//' not used: '//reason//'; nothing was changed'
    end function refused_access

    !> The counters of the hydrodynamic model (kf_hydro_model's hydro_stats_t), cumulative over
    !> resumes: saved with every checkpoint and written as the root attributes
    !> hydro.{evaluations, refreshes, reused, cg_iterations}.
    function hydro_counts() result(c)
      integer(i8) :: c(4)
      type(hydro_stats_t) :: st
      st = dyn%hydro_statistics()
      c = hydro_base + [st%evaluations, st%refreshes, st%reused, st%cg_iterations]
    end function hydro_counts

    subroutine write_hydro_counters(err)
      type(error_t), allocatable, intent(out) :: err
      integer(i8) :: c(4)
      integer :: k
      c = hydro_counts()
      do k = 1, 4
        call file%write_attribute(trim(hydro_counters(k)), c(k), err)
        if (allocated(err)) return
      end do
    end subroutine write_hydro_counters

    !> The counters of the run before the resume: from its checkpoint, or (files written before
    !> the checkpoint held them) from the root attributes.
    subroutine read_hydro_counters(err)
      type(error_t), allocatable, intent(out) :: err
      integer :: k
      if (allocated(saved_counters)) then
        if (size(saved_counters) /= size(hydro_base)) then
          call fatal_error(err, path//': the checkpoint holds '//to_str(size(saved_counters))// &
            ' run counters, not '//to_str(size(hydro_base)))
          return
        end if
        hydro_base = saved_counters
        return
      end if
      do k = 1, 4
        call file%read_counter(trim(hydro_counters(k)), hydro_base(k), err)
        if (allocated(err)) return
      end do
    end subroutine read_hydro_counters

    !> The run diagnostics' state from the checkpoint the file resumed from.
    subroutine restore_diagnostics(err)
      type(error_t), allocatable, intent(out) :: err
      integer(i8), allocatable :: counters(:)
      real(wp), allocatable :: values(:), ongoing(:, :)
      call file%resumed_diagnostics(counters, values, ongoing, err)
      if (allocated(err)) return
      call diag%set_state(counters, values, ongoing, err)
      if (allocated(err)) err%message = "case file '"//path//"': "//err%message
    end subroutine restore_diagnostics

    !> The record of the frame just computed (kf_frame_records) with the fibre's stresslet when
    !> the file holds it; `error` from the shape or the stresslet.
    subroutine record_frame()
      call fill_frame(frame, t, r, integ, error, diag)
      if (.not. allocated(error) .and. allocated(frame%stresslet)) call dyn%stresslet(r, frame%stresslet, error)
    end subroutine record_frame

    !> The stepper's state from the checkpoint: the whole state when the file has it, else
    !> (files written before) the step size and step counts.
    subroutine restore_stepper(err)
      type(error_t), allocatable, intent(out) :: err
      if (allocated(saved%ints)) then
        if (saved%name /= trim(sc%integrator%method)) then
          call fatal_error(err, path//": the checkpoint holds the state of stepper '"//saved%name// &
            "', not of '"//trim(sc%integrator%method)//"'")
          return
        end if
        call integ%set_state(saved%reals, saved%ints, err)
      else
        call integ%set_basic_state(dt, steps, rejected, err)
      end if
      if (allocated(err)) err%message = path//': '//err%message
    end subroutine restore_stepper

    !> The case cannot be computed (integration failure): recorded as status 'failed: <reason>'
    !> (the next run computes it again from the start).
    subroutine fail(reason)
      character(len=*), intent(in) :: reason
      type(error_t), allocatable :: err
      status = case_failed
      message = reason
      call file%set_status('failed: '//reason, err)
      if (allocated(err)) then
        call file%close()
      else
        call file%close(err)
      end if
      if (allocated(err)) message = message//' (the case file could not record it: '//err%message//')'
    end subroutine fail

    !> A stop signal arrived (kf_signals): the frame just written and its checkpoint are whole;
    !> the file is closed with status 'running', so that the next run resumes it here.
    subroutine stopped()
      type(error_t), allocatable :: err
      status = case_stopped
      message = 'stopped by '//signal_name(stop_signal())//' at t = '//to_str_exact(t)// &
        ' (its frame and checkpoint written): the next run resumes it there'
      call file%close(err)
      if (allocated(err)) message = message//' (closing the case file failed: '//err%message//')'
    end subroutine stopped

    !> Writing the case file failed (full disk, file size limit, I/O error): the case fails
    !> with the reason, the file keeps its status 'running' and its last complete checkpoint,
    !> from which the next run resumes.
    subroutine write_failed(reason)
      character(len=*), intent(in) :: reason
      character(len=:), allocatable :: short
      integer :: k
      status = case_failed
      ! the summary line names the file already: keep the message short
      short = reason
      k = index(short, " in file '"//path//"'")
      if (k > 0) short = short(1:k - 1)//short(k + len(" in file '"//path//"'"):)
      if (file%checkpoint_time() >= 0.0_wp) then
        message = 'write failed: '//short//'; not marked finished, the next run resumes it from its '// &
          'last complete checkpoint (t = '//to_str_exact(file%checkpoint_time())//')'
      else
        message = 'write failed: '//short//'; no checkpoint yet, the next run computes the case again'
      end if
      call file%close()
    end subroutine write_failed

    function progress_line() result(line)
      character(len=:), allocatable :: line
      real(wp) :: elapsed, eta
      type(hydro_stats_t) :: st
      elapsed = real(clock_now - clock0, wp)/rate
      eta = elapsed*(sc%integrator%t_end - t)/max(t - t_start, tiny(1.0_wp))
      line = 'case '//name//': t = '//to_str_short(t)//' / '//to_str_short(sc%integrator%t_end)//', dt = '// &
             to_str_short(integ%dt())//', steps = '//to_str(integ%steps())//' ('//to_str(integ%rejected())// &
             ' rejected), elapsed '//to_str_short(elapsed)//' s, ETA '//to_str_short(eta)//' s'
      st = dyn%hydro_statistics()
      if (st%reused > 0) line = line//', hydro: '//to_str(hydro_base(2) + st%refreshes)//' refreshes, '// &
        to_str(hydro_base(3) + st%reused)//' reused, '//to_str(hydro_base(4) + st%cg_iterations)// &
        ' CG iterations, refreshing '//to_str(nint(100*st%refresh_seconds/ &
        max(st%refresh_seconds + st%reused_seconds, tiny(1.0_wp))))//' % of the model time'
    end function progress_line

  end subroutine run_case

  !> Every effective scene variable as a root attribute `<group>.<variable>`.
  subroutine write_scene_attributes(file, sc, error)
    type(case_file_t), intent(inout) :: file
    type(scene_t), intent(in) :: sc
    type(error_t), allocatable, intent(out) :: error
    type(scene_item_t), allocatable :: items(:)
    integer :: k
    call scene_items(sc, items)
    do k = 1, size(items)
      associate (it => items(k))
        select case (it%kind)
        case (item_string)
          call file%write_attribute(trim(it%name), it%s, error)
        case (item_integer, item_logical)
          call file%write_attribute(trim(it%name), it%i, error)
        case (item_real)
          call file%write_attribute(trim(it%name), it%r, error)
        case (item_real_array)
          if (it%dims(2) > 0) then
            call file%write_attribute(trim(it%name), reshape(it%ra, it%dims), error)
          else
            call file%write_attribute(trim(it%name), it%ra, error)
          end if
        end select
      end associate
      if (allocated(error)) return
    end do
  end subroutine write_scene_attributes

end module kf_case_runner
