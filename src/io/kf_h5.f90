!> The one module of knotflow that talks to HDF5.
!>
!> Every `h5*_f` status is checked and turned into an `error_t` naming the file and the object.
!> The HDF5 library is initialised once per program with `h5_initialize` (which also switches
!> off HDF5's own error printing: the library never prints) and closed with `h5_finalize`.
!> Apart from what the HDF5 library keeps itself there is no module state.
!>
!> Arrays are written in Fortran order, so a Fortran array a(3, n, m) appears in h5py (C order)
!> with shape (m, n, 3). Extendible datasets grow along their last Fortran dimension (the first
!> axis as seen from h5py). Strings are written as fixed-length, null-padded ASCII; strings are
!> read both in that form and as variable-length strings (what h5py writes by default).
!> Chunked (extendible) datasets carry HDF5's Fletcher-32 checksum filter, so damaged data fails
!> to read instead of reading wrong. Failed writes, flushes and closes name the operating
!> system's reason (errno, kf_fs).
!> Writing an attribute that exists overwrites it in place when its type and shape match and
!> replaces it otherwise; writing a dataset that exists overwrites it in
!> place when the shape matches (no file space is lost) and replaces it otherwise.
module kf_h5
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_char, &
    c_associated, c_int, c_null_char
  use, intrinsic :: iso_fortran_env, only: int32, int64
  use kf_kinds, only: wp, i4, i8
  use kf_strings, only: to_str, chars_to_string, c_string
  use kf_error, only: error_t, fatal_error
  use kf_fs, only: clear_os_error, os_error_text
  use hdf5, only: hid_t, hsize_t, size_t, h5open_f, h5close_f, h5eset_auto_f, &
    h5fcreate_f, h5fopen_f, h5fclose_f, h5fflush_f, H5F_ACC_TRUNC_F, H5F_ACC_RDWR_F, &
    H5F_ACC_RDONLY_F, H5F_SCOPE_GLOBAL_F, h5gcreate_f, h5gclose_f, h5lexists_f, h5ldelete_f, h5lmove_f, &
    h5oopen_f, h5oclose_f, h5screate_f, h5screate_simple_f, h5sclose_f, H5S_SCALAR_F, &
    H5S_UNLIMITED_F, H5S_SELECT_SET_F, h5sget_simple_extent_ndims_f, &
    h5sget_simple_extent_dims_f, h5sselect_hyperslab_f, h5acreate_f, h5aopen_f, h5aclose_f, &
    h5aexists_f, h5adelete_f, h5awrite_f, h5aread_f, h5aget_type_f, h5aget_space_f, &
    h5dcreate_f, h5dopen_f, h5dclose_f, h5dwrite_f, h5dread_f, h5dget_space_f, &
    h5dset_extent_f, h5pcreate_f, h5pclose_f, h5pset_chunk_f, h5pset_fletcher32_f, H5P_DATASET_CREATE_F, &
    h5tcopy_f, h5tclose_f, h5tequal_f, h5tset_size_f, h5tget_size_f, h5tset_strpad_f, h5tget_class_f, &
    h5tis_variable_str_f, H5T_FORTRAN_S1, H5T_STR_NULLPAD_F, H5T_STRING_F, H5T_FLOAT_F, H5T_INTEGER_F, &
    h5dget_type_f, &
    H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, H5T_STD_I32LE, H5T_STD_I64LE, h5kind_to_type, &
    H5_INTEGER_KIND
  implicit none
  private

  public :: h5_file_t
  public :: h5_initialize, h5_finalize
  public :: h5_create_file, h5_open_file, h5_close_file, h5_flush
  public :: h5_create_group, h5_exists, h5_attr_exists, h5_delete, h5_move
  public :: h5_write_attr, h5_read_attr
  public :: h5_write, h5_read
  public :: h5_create_extendible, h5_append, h5_set_length, h5_length, h5_read_entry
  public :: h5_extend_truncated, h5_raise_end
  public :: h5_real, h5_int32, h5_int64

  !> Element kinds of extendible datasets (for `h5_create_extendible`).
  integer, parameter :: h5_real = 1, h5_int32 = 2, h5_int64 = 3

  !> An open HDF5 file and its path (for error messages).
  type :: h5_file_t
    private
    integer(hid_t) :: id = -1
    character(len=:), allocatable :: path
  contains
    procedure :: is_open => file_is_open
    procedure :: name => file_name
  end type h5_file_t

  !> Write an attribute `name` on object `obj` ('/' for the root): character string, int32,
  !> int64, real(wp) scalar, 1-D or 2-D real(wp) array, or 1-D array of strings.
  interface h5_write_attr
    module procedure write_attr_str, write_attr_i4, write_attr_i8, write_attr_r, &
      write_attr_r1, write_attr_r2, write_attr_str1
  end interface h5_write_attr

  !> Read an attribute written by `h5_write_attr` (values convert between numeric kinds).
  interface h5_read_attr
    module procedure read_attr_str, read_attr_i4, read_attr_i8, read_attr_r, &
      read_attr_r1, read_attr_r2
  end interface h5_read_attr

  !> Write a whole dataset: real(wp), int32 or int64 scalar or 1-D/2-D/3-D array, or a 1-D
  !> array of strings.
  interface h5_write
    module procedure write_r0, write_r1, write_r2, write_r3, write_i4_0, write_i4_1, &
      write_i4_2, write_i4_3, write_i8_0, write_i8_1, write_i8_2, write_i8_3, write_str1
  end interface h5_write

  !> Read a whole dataset into an allocatable (or scalar) variable of matching rank.
  interface h5_read
    module procedure read_r0, read_r1, read_r2, read_r3, read_i4_0, read_i4_1, read_i4_2, &
      read_i4_3, read_i8_0, read_i8_1, read_i8_2, read_i8_3
  end interface h5_read

  !> Append one entry along the last (extendible) dimension: a scalar to a 1-D dataset,
  !> a 1-D array to a 2-D dataset, a 2-D array to a 3-D dataset.
  interface h5_append
    module procedure append_r0, append_r1, append_r2, append_i4_0, append_i8_0
  end interface h5_append

  interface
    function c_h5free_memory(p) bind(c, name='H5free_memory') result(status)
      import :: c_ptr, c_int
      type(c_ptr), value :: p
      integer(c_int) :: status
    end function c_h5free_memory
  end interface

contains

  ! ---------------------------------------------------------------- library and files

  !> Initialise the HDF5 library (once per program) and switch off its error printing.
  subroutine h5_initialize(error)
    type(error_t), allocatable, intent(out) :: error
    integer :: stat
    call h5open_f(stat)
    if (stat < 0) then
      call fatal_error(error, 'HDF5: cannot initialise the library (h5open_f)')
      return
    end if
    call h5eset_auto_f(0, stat)
    if (stat < 0) call fatal_error(error, 'HDF5: cannot switch off error printing (h5eset_auto_f)')
  end subroutine h5_initialize

  !> Close the HDF5 library (once per program, after all files are closed).
  subroutine h5_finalize(error)
    type(error_t), allocatable, intent(out), optional :: error
    integer :: stat
    call h5close_f(stat)
    if (stat < 0 .and. present(error)) call fatal_error(error, 'HDF5: cannot close the library (h5close_f)')
  end subroutine h5_finalize

  !> True when the file is open.
  pure logical function file_is_open(this)
    class(h5_file_t), intent(in) :: this
    file_is_open = this%id >= 0
  end function file_is_open

  !> The file's path ('' when never opened).
  pure function file_name(this) result(path)
    class(h5_file_t), intent(in) :: this
    character(len=:), allocatable :: path
    if (allocated(this%path)) then
      path = this%path
    else
      path = ''
    end if
  end function file_name

  !> Create (truncate) a file for writing. Fails cleanly when the directory is not writable.
  subroutine h5_create_file(file, path, error)
    type(h5_file_t), intent(out) :: file
    character(len=*), intent(in) :: path
    type(error_t), allocatable, intent(out) :: error
    integer :: stat
    file%path = path
    call clear_os_error()
    call h5fcreate_f(path, H5F_ACC_TRUNC_F, file%id, stat)
    if (stat < 0) then
      file%id = -1
      call fatal_error(error, "HDF5: cannot create file '"//path//"'"//os_reason())
    end if
  end subroutine h5_create_file

  !> Open an existing file, read-only or for reading and writing.
  subroutine h5_open_file(file, path, writable, error)
    type(h5_file_t), intent(out) :: file
    character(len=*), intent(in) :: path
    logical, intent(in) :: writable
    type(error_t), allocatable, intent(out) :: error
    integer :: stat
    logical :: exists
    file%path = path
    inquire (file=path, exist=exists)
    if (.not. exists) then
      call fatal_error(error, "HDF5: file '"//path//"' does not exist")
      return
    end if
    if (writable) then
      call h5fopen_f(path, H5F_ACC_RDWR_F, file%id, stat)
    else
      call h5fopen_f(path, H5F_ACC_RDONLY_F, file%id, stat)
    end if
    if (stat < 0) then
      file%id = -1
      call fatal_error(error, "HDF5: cannot open file '"//path//"' ("//unopenable_reason(path)//')')
    end if
  end subroutine h5_open_file

  !> Why HDF5 cannot open the existing `path`: a directory, an empty file, no HDF5 signature in
  !> its first 8 bytes, or (with the signature) a truncated or damaged file.
  function unopenable_reason(path) result(reason)
    character(len=*), intent(in) :: path
    character(len=:), allocatable :: reason
    character(len=7), parameter :: signature_tail = 'HDF'//achar(13)//achar(10)//achar(26)//achar(10)
    character(len=8) :: head
    integer :: unit, stat
    integer(i8) :: bytes
    logical :: is_dir
    inquire (file=path//'/.', exist=is_dir)
    if (is_dir) then
      reason = 'it is a directory'
      return
    end if
    open (newunit=unit, file=path, access='stream', form='unformatted', action='read', status='old', iostat=stat)
    if (stat /= 0) then
      reason = 'not readable'
      return
    end if
    inquire (unit=unit, size=bytes)
    head = ''
    if (bytes >= 8) read (unit, iostat=stat) head
    close (unit)
    if (bytes == 0) then
      reason = 'an empty file, not HDF5'
    else if (iachar(head(1:1)) /= 137 .or. head(2:8) /= signature_tail) then
      reason = 'not an HDF5 file'
    else
      reason = 'an HDF5 file that is truncated or damaged'
    end if
  end function unopenable_reason

  !> Close the file (a closed file is left alone).
  subroutine h5_close_file(file, error)
    type(h5_file_t), intent(inout) :: file
    type(error_t), allocatable, intent(out), optional :: error
    integer :: stat
    if (file%id < 0) return
    call clear_os_error()
    call h5fclose_f(file%id, stat)
    file%id = -1
    if (stat < 0 .and. present(error)) call fatal_error(error, "HDF5: cannot close file '"//file%name()// &
      "' (its last writes may be lost)"//os_reason())
  end subroutine h5_close_file

  !> Flush all buffers of the file to disk (H5Fflush).
  subroutine h5_flush(file, error)
    type(h5_file_t), intent(in) :: file
    type(error_t), allocatable, intent(out) :: error
    integer :: stat
    call clear_os_error()
    call h5fflush_f(file%id, H5F_SCOPE_GLOBAL_F, stat)
    if (stat < 0) call fail_io(error, file, 'flush', '/')
  end subroutine h5_flush

  ! ---------------------------------------------------------------- groups and links

  !> Create group `name` (an absolute path like '/frames/observables'), with any missing parents.
  !> An existing group is not an error.
  subroutine h5_create_group(file, name, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    type(error_t), allocatable, intent(out) :: error
    integer(hid_t) :: gid
    integer :: stat, i
    logical :: exists
    do i = 2, len(name) + 1
      if (i <= len(name)) then
        if (name(i:i) /= '/') cycle
      end if
      call h5lexists_f(file%id, name(1:i - 1), exists, stat)
      if (stat < 0) then
        call fail(error, file, 'check existence of', name(1:i - 1))
        return
      end if
      if (exists) cycle
      call h5gcreate_f(file%id, name(1:i - 1), gid, stat)
      if (stat < 0) then
        call fail(error, file, 'create group', name(1:i - 1))
        return
      end if
      call h5gclose_f(gid, stat)
      if (stat < 0) then
        call fail(error, file, 'close group', name(1:i - 1))
        return
      end if
    end do
  end subroutine h5_create_group

  !> True when the object (group or dataset) `name` exists; every parent is checked in turn.
  !> Any HDF5 failure counts as "does not exist". '/' always exists in an open file.
  logical function h5_exists(file, name) result(exists)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer :: stat, i
    exists = file%id >= 0
    if (.not. exists .or. name == '/' .or. len(name) == 0) return
    do i = 2, len(name) + 1
      if (i <= len(name)) then
        if (name(i:i) /= '/') cycle
      end if
      call h5lexists_f(file%id, name(1:i - 1), exists, stat)
      if (stat < 0) exists = .false.
      if (.not. exists) return
    end do
  end function h5_exists

  !> True when object `obj` exists and carries attribute `name`.
  logical function h5_attr_exists(file, obj, name) result(exists)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    integer(hid_t) :: oid
    integer :: stat
    exists = h5_exists(file, obj)
    if (.not. exists) return
    call h5oopen_f(file%id, obj, oid, stat)
    if (stat < 0) then
      exists = .false.
      return
    end if
    call h5aexists_f(oid, name, exists, stat)
    if (stat < 0) exists = .false.
    call h5oclose_f(oid, stat)
  end function h5_attr_exists

  ! ---------------------------------------------------------------- attributes: writing

  subroutine write_attr_str(file, obj, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name, value
    type(error_t), allocatable, intent(out) :: error
    character(kind=c_char), allocatable, target :: buf(:)
    integer(hid_t) :: tid
    integer :: stat, i
    allocate (buf(max(1, len(value))))
    buf = c_null_char
    do i = 1, len(value)
      buf(i) = value(i:i)
    end do
    call make_string_type(size(buf), tid, stat)
    if (stat < 0) then
      call fail(error, file, 'create string type for attribute', obj//'@'//name)
      return
    end if
    call write_attr_raw(file, obj, name, tid, tid, [integer(hsize_t) ::], c_loc(buf), error)
    call h5tclose_f(tid, stat)
  end subroutine write_attr_str

  subroutine write_attr_str1(file, obj, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name, value(:)
    type(error_t), allocatable, intent(out) :: error
    character(kind=c_char), allocatable, target :: buf(:, :)
    integer(hid_t) :: tid
    integer :: stat
    call pack_strings(value, buf)
    call make_string_type(size(buf, 1), tid, stat)
    if (stat < 0) then
      call fail(error, file, 'create string type for attribute', obj//'@'//name)
      return
    end if
    call write_attr_raw(file, obj, name, tid, tid, [integer(hsize_t) :: size(value)], c_loc(buf), error)
    call h5tclose_f(tid, stat)
  end subroutine write_attr_str1

  subroutine write_attr_i4(file, obj, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    integer(i4), intent(in) :: value
    type(error_t), allocatable, intent(out) :: error
    integer(i4), target :: buf(1)
    buf(1) = value
    call write_attr_raw(file, obj, name, h5kind_to_type(int32, H5_INTEGER_KIND), H5T_STD_I32LE, &
      [integer(hsize_t) ::], c_loc(buf), error)
  end subroutine write_attr_i4

  subroutine write_attr_i8(file, obj, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    integer(i8), intent(in) :: value
    type(error_t), allocatable, intent(out) :: error
    integer(i8), target :: buf(1)
    buf(1) = value
    call write_attr_raw(file, obj, name, h5kind_to_type(int64, H5_INTEGER_KIND), H5T_STD_I64LE, &
      [integer(hsize_t) ::], c_loc(buf), error)
  end subroutine write_attr_i8

  subroutine write_attr_r(file, obj, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    real(wp), intent(in) :: value
    type(error_t), allocatable, intent(out) :: error
    real(wp), target :: buf(1)
    buf(1) = value
    call write_attr_raw(file, obj, name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, [integer(hsize_t) ::], &
      c_loc(buf), error)
  end subroutine write_attr_r

  subroutine write_attr_r1(file, obj, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    real(wp), intent(in), target, contiguous :: value(:)
    type(error_t), allocatable, intent(out) :: error
    call write_attr_raw(file, obj, name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, &
      int(shape(value), hsize_t), c_loc(value), error)
  end subroutine write_attr_r1

  subroutine write_attr_r2(file, obj, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    real(wp), intent(in), target, contiguous :: value(:, :)
    type(error_t), allocatable, intent(out) :: error
    call write_attr_raw(file, obj, name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, &
      int(shape(value), hsize_t), c_loc(value), error)
  end subroutine write_attr_r2

  !> Write an attribute; rank 0 dims means a scalar. An existing attribute of the same type and
  !> shape is overwritten in place (its object header keeps its structure, so a kill while the
  !> header is flushed leaves the old or the new value); one of another type or shape is
  !> replaced.
  subroutine write_attr_raw(file, obj, name, memtype, filetype, dims, buf, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    integer(hid_t), intent(in) :: memtype, filetype
    integer(hsize_t), intent(in) :: dims(:)
    type(c_ptr), intent(in) :: buf
    type(error_t), allocatable, intent(out) :: error
    integer(hid_t) :: oid, sid, aid
    integer :: stat, ignore
    logical :: exists, same
    call h5oopen_f(file%id, obj, oid, stat)
    if (stat < 0) then
      call fail(error, file, 'open object', obj)
      return
    end if
    call h5aexists_f(oid, name, exists, stat)
    if (stat >= 0 .and. exists) then
      call h5aopen_f(oid, name, aid, stat)
      if (stat >= 0) then
        same = same_type_and_shape(aid, filetype, dims)
        if (same) then
          call clear_os_error()
          call h5awrite_f(aid, memtype, buf, stat)
          if (stat < 0) call fail_io(error, file, 'write attribute', obj//'@'//name)
        end if
        call h5aclose_f(aid, stat)
        if (stat < 0 .and. .not. allocated(error)) call fail_io(error, file, 'write (close) attribute', obj//'@'//name)
        if (same .or. allocated(error)) then
          call h5oclose_f(oid, ignore)
          return
        end if
      end if
      if (stat >= 0) call h5adelete_f(oid, name, stat)
    end if
    if (stat < 0) then
      call fail(error, file, 'replace attribute', obj//'@'//name)
      call h5oclose_f(oid, ignore)
      return
    end if
    if (size(dims) == 0) then
      call h5screate_f(H5S_SCALAR_F, sid, stat)
    else
      call h5screate_simple_f(size(dims), dims, sid, stat)
    end if
    if (stat < 0) then
      call fail(error, file, 'create dataspace for attribute', obj//'@'//name)
      call h5oclose_f(oid, ignore)
      return
    end if
    call h5acreate_f(oid, name, filetype, sid, aid, stat)
    if (stat < 0) then
      call fail_io(error, file, 'create attribute', obj//'@'//name)
    else
      call clear_os_error()
      call h5awrite_f(aid, memtype, buf, stat)
      if (stat < 0) call fail_io(error, file, 'write attribute', obj//'@'//name)
      call h5aclose_f(aid, stat)
      if (stat < 0 .and. .not. allocated(error)) call fail_io(error, file, 'write (close) attribute', obj//'@'//name)
    end if
    call h5sclose_f(sid, ignore)
    call h5oclose_f(oid, ignore)
  end subroutine write_attr_raw

  !> Has the open attribute `aid` the file type `filetype` and the dimensions `dims`?
  logical function same_type_and_shape(aid, filetype, dims) result(same)
    integer(hid_t), intent(in) :: aid, filetype
    integer(hsize_t), intent(in) :: dims(:)
    integer(hid_t) :: tid, sid
    integer(hsize_t), allocatable :: old(:)
    integer :: stat, ignore
    same = .false.
    call h5aget_type_f(aid, tid, stat)
    if (stat < 0) return
    call h5tequal_f(tid, filetype, same, stat)
    if (stat < 0) same = .false.
    call h5tclose_f(tid, ignore)
    if (.not. same) return
    call h5aget_space_f(aid, sid, stat)
    same = stat >= 0
    if (.not. same) return
    call space_dims(sid, -1, old, stat)
    same = stat >= 0
    if (same) same = size(old) == size(dims)
    if (same) same = all(old == dims)
    call h5sclose_f(sid, ignore)
  end function same_type_and_shape

  ! ---------------------------------------------------------------- attributes: reading

  subroutine read_attr_str(file, obj, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    character(len=:), allocatable, intent(out) :: value
    type(error_t), allocatable, intent(out) :: error
    integer(hid_t) :: oid, aid, tid, memtype
    integer(size_t) :: n
    integer :: stat, ignore, tclass
    logical :: is_vlen
    character(kind=c_char), allocatable, target :: buf(:)
    type(c_ptr), target :: vbuf(1)
    type(c_ptr) :: ptr
    call open_attr(file, obj, name, oid, aid, error)
    if (allocated(error)) return
    call h5aget_type_f(aid, tid, stat)
    if (stat >= 0) call h5tget_class_f(tid, tclass, stat)
    if (stat < 0) then
      call fail(error, file, 'get type of attribute', obj//'@'//name)
    else if (tclass /= H5T_STRING_F) then
      call fatal_error(error, "HDF5: attribute '"//obj//'@'//name//"' in '"//file%name()//"' is not a string")
    else
      call h5tis_variable_str_f(tid, is_vlen, stat)
      if (stat < 0) then
        call fail(error, file, 'get string kind of attribute', obj//'@'//name)
      else if (is_vlen) then
        ! Variable-length string (h5py's default): read the C pointer, copy, free.
        vbuf(1) = c_null()
        ptr = c_loc(vbuf)
        call h5aread_f(aid, tid, ptr, stat)
        if (stat < 0) then
          call fail(error, file, 'read attribute', obj//'@'//name)
        else
          value = c_string(vbuf(1))
          if (c_associated(vbuf(1))) ignore = c_h5free_memory(vbuf(1))
        end if
      else
        call h5tget_size_f(tid, n, stat)
        if (stat >= 0) call make_string_type(int(n), memtype, stat)
        if (stat < 0) then
          call fail(error, file, 'get size of attribute', obj//'@'//name)
        else
          allocate (buf(n))
          ptr = c_loc(buf)
          call h5aread_f(aid, memtype, ptr, stat)
          if (stat < 0) then
            call fail(error, file, 'read attribute', obj//'@'//name)
          else
            value = chars_to_string(buf)
          end if
          call h5tclose_f(memtype, ignore)
        end if
      end if
      call h5tclose_f(tid, ignore)
    end if
    call h5aclose_f(aid, ignore)
    call h5oclose_f(oid, ignore)
  end subroutine read_attr_str

  subroutine read_attr_i4(file, obj, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    integer(i4), intent(out) :: value
    type(error_t), allocatable, intent(out) :: error
    integer(i4), target :: buf(1)
    integer(hsize_t), allocatable :: dims(:)
    call read_attr_raw(file, obj, name, h5kind_to_type(int32, H5_INTEGER_KIND), 0, dims, c_loc(buf), error)
    if (.not. allocated(error)) value = buf(1)
  end subroutine read_attr_i4

  subroutine read_attr_i8(file, obj, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    integer(i8), intent(out) :: value
    type(error_t), allocatable, intent(out) :: error
    integer(i8), target :: buf(1)
    integer(hsize_t), allocatable :: dims(:)
    call read_attr_raw(file, obj, name, h5kind_to_type(int64, H5_INTEGER_KIND), 0, dims, c_loc(buf), error)
    if (.not. allocated(error)) value = buf(1)
  end subroutine read_attr_i8

  subroutine read_attr_r(file, obj, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    real(wp), intent(out) :: value
    type(error_t), allocatable, intent(out) :: error
    real(wp), target :: buf(1)
    integer(hsize_t), allocatable :: dims(:)
    call read_attr_raw(file, obj, name, H5T_NATIVE_DOUBLE, 0, dims, c_loc(buf), error)
    if (.not. allocated(error)) value = buf(1)
  end subroutine read_attr_r

  subroutine read_attr_r1(file, obj, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    real(wp), allocatable, target, intent(out) :: value(:)
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: dims(:)
    call attr_dims(file, obj, name, 1, dims, error)
    if (allocated(error)) return
    allocate (value(dims(1)))
    call read_attr_raw(file, obj, name, H5T_NATIVE_DOUBLE, 1, dims, c_loc(value), error)
  end subroutine read_attr_r1

  subroutine read_attr_r2(file, obj, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    real(wp), allocatable, target, intent(out) :: value(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: dims(:)
    call attr_dims(file, obj, name, 2, dims, error)
    if (allocated(error)) return
    allocate (value(dims(1), dims(2)))
    call read_attr_raw(file, obj, name, H5T_NATIVE_DOUBLE, 2, dims, c_loc(value), error)
  end subroutine read_attr_r2

  !> Dimensions (Fortran order) of an attribute, which must have rank `rank`.
  subroutine attr_dims(file, obj, name, rank, dims, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    integer, intent(in) :: rank
    integer(hsize_t), allocatable, intent(out) :: dims(:)
    type(error_t), allocatable, intent(out) :: error
    integer(hid_t) :: oid, aid, sid
    integer :: stat, ignore
    call open_attr(file, obj, name, oid, aid, error)
    if (allocated(error)) return
    call h5aget_space_f(aid, sid, stat)
    if (stat < 0) then
      call fail(error, file, 'get dataspace of attribute', obj//'@'//name)
    else
      call space_dims(sid, rank, dims, stat)
      if (stat < 0) call fatal_error(error, "HDF5: attribute '"//obj//'@'//name//"' in '"// &
        file%name()//"' does not have rank "//to_str(rank))
      call h5sclose_f(sid, ignore)
    end if
    call h5aclose_f(aid, ignore)
    call h5oclose_f(oid, ignore)
  end subroutine attr_dims

  !> Read a numeric attribute into `buf`; a scalar request (rank 0) accepts a scalar or
  !> a one-element attribute.
  subroutine read_attr_raw(file, obj, name, memtype, rank, dims, buf, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    integer(hid_t), intent(in) :: memtype
    integer, intent(in) :: rank
    integer(hsize_t), allocatable, intent(inout) :: dims(:)
    type(c_ptr), intent(in) :: buf
    type(error_t), allocatable, intent(out) :: error
    integer(hid_t) :: oid, aid, sid
    integer :: stat, ignore
    integer(hsize_t), allocatable :: fdims(:)
    type(c_ptr) :: ptr
    call open_attr(file, obj, name, oid, aid, error)
    if (allocated(error)) return
    call h5aget_space_f(aid, sid, stat)
    if (stat < 0) then
      call fail(error, file, 'get dataspace of attribute', obj//'@'//name)
    else
      call space_dims(sid, -1, fdims, stat)
      if (stat < 0) then
        call fail(error, file, 'get dimensions of attribute', obj//'@'//name)
      else if (rank == 0 .and. product(fdims) /= 1) then
        call fatal_error(error, "HDF5: attribute '"//obj//'@'//name//"' in '"//file%name()// &
          "' is not a scalar")
      else if (rank > 0) then
        if (size(fdims) /= rank) then
          call fatal_error(error, "HDF5: attribute '"//obj//'@'//name//"' in '"//file%name()// &
            "' does not have rank "//to_str(rank))
        else if (any(fdims /= dims)) then
          call fatal_error(error, "HDF5: attribute '"//obj//'@'//name//"' in '"//file%name()// &
            "' changed shape while reading")
        end if
      end if
      call h5sclose_f(sid, ignore)
    end if
    if (.not. allocated(error)) then
      ptr = buf
      call h5aread_f(aid, memtype, ptr, stat)
      if (stat < 0) call fail(error, file, 'read attribute', obj//'@'//name)
    end if
    call h5aclose_f(aid, ignore)
    call h5oclose_f(oid, ignore)
  end subroutine read_attr_raw

  subroutine open_attr(file, obj, name, oid, aid, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: obj, name
    integer(hid_t), intent(out) :: oid, aid
    type(error_t), allocatable, intent(out) :: error
    integer :: stat, ignore
    logical :: exists
    call h5oopen_f(file%id, obj, oid, stat)
    if (stat < 0) then
      call fail(error, file, 'open object', obj)
      return
    end if
    call h5aexists_f(oid, name, exists, stat)
    if (stat < 0 .or. .not. exists) then
      call fatal_error(error, "HDF5: attribute '"//obj//'@'//name//"' not found in '"//file%name()//"'")
      call h5oclose_f(oid, ignore)
      return
    end if
    call h5aopen_f(oid, name, aid, stat)
    if (stat < 0) then
      call fail(error, file, 'open attribute', obj//'@'//name)
      call h5oclose_f(oid, ignore)
    end if
  end subroutine open_attr

  ! ---------------------------------------------------------------- datasets: whole writes

  subroutine write_r0(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value
    type(error_t), allocatable, intent(out) :: error
    real(wp), target :: buf(1)
    buf(1) = value
    call write_raw(file, name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, [integer(hsize_t) ::], c_loc(buf), error)
  end subroutine write_r0

  subroutine write_r1(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in), target, contiguous :: value(:)
    type(error_t), allocatable, intent(out) :: error
    call write_raw(file, name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, int(shape(value), hsize_t), c_loc(value), error)
  end subroutine write_r1

  subroutine write_r2(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in), target, contiguous :: value(:, :)
    type(error_t), allocatable, intent(out) :: error
    call write_raw(file, name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, int(shape(value), hsize_t), c_loc(value), error)
  end subroutine write_r2

  subroutine write_r3(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in), target, contiguous :: value(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    call write_raw(file, name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, int(shape(value), hsize_t), c_loc(value), error)
  end subroutine write_r3

  subroutine write_i4_0(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i4), intent(in) :: value
    type(error_t), allocatable, intent(out) :: error
    integer(i4), target :: buf(1)
    buf(1) = value
    call write_raw(file, name, h5kind_to_type(int32, H5_INTEGER_KIND), H5T_STD_I32LE, [integer(hsize_t) ::], &
      c_loc(buf), error)
  end subroutine write_i4_0

  subroutine write_i4_1(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i4), intent(in), target, contiguous :: value(:)
    type(error_t), allocatable, intent(out) :: error
    call write_raw(file, name, h5kind_to_type(int32, H5_INTEGER_KIND), H5T_STD_I32LE, int(shape(value), hsize_t), &
      c_loc(value), error)
  end subroutine write_i4_1

  subroutine write_i4_2(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i4), intent(in), target, contiguous :: value(:, :)
    type(error_t), allocatable, intent(out) :: error
    call write_raw(file, name, h5kind_to_type(int32, H5_INTEGER_KIND), H5T_STD_I32LE, int(shape(value), hsize_t), &
      c_loc(value), error)
  end subroutine write_i4_2

  subroutine write_i4_3(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i4), intent(in), target, contiguous :: value(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    call write_raw(file, name, h5kind_to_type(int32, H5_INTEGER_KIND), H5T_STD_I32LE, int(shape(value), hsize_t), &
      c_loc(value), error)
  end subroutine write_i4_3

  subroutine write_i8_0(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(in) :: value
    type(error_t), allocatable, intent(out) :: error
    integer(i8), target :: buf(1)
    buf(1) = value
    call write_raw(file, name, h5kind_to_type(int64, H5_INTEGER_KIND), H5T_STD_I64LE, [integer(hsize_t) ::], &
      c_loc(buf), error)
  end subroutine write_i8_0

  subroutine write_i8_1(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(in), target, contiguous :: value(:)
    type(error_t), allocatable, intent(out) :: error
    call write_raw(file, name, h5kind_to_type(int64, H5_INTEGER_KIND), H5T_STD_I64LE, int(shape(value), hsize_t), &
      c_loc(value), error)
  end subroutine write_i8_1

  subroutine write_i8_2(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(in), target, contiguous :: value(:, :)
    type(error_t), allocatable, intent(out) :: error
    call write_raw(file, name, h5kind_to_type(int64, H5_INTEGER_KIND), H5T_STD_I64LE, int(shape(value), hsize_t), &
      c_loc(value), error)
  end subroutine write_i8_2

  subroutine write_i8_3(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(in), target, contiguous :: value(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    call write_raw(file, name, h5kind_to_type(int64, H5_INTEGER_KIND), H5T_STD_I64LE, int(shape(value), hsize_t), &
      c_loc(value), error)
  end subroutine write_i8_3

  !> A 1-D dataset of fixed-length strings (length of the longest, at least 1).
  subroutine write_str1(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    character(len=*), intent(in) :: value(:)
    type(error_t), allocatable, intent(out) :: error
    character(kind=c_char), allocatable, target :: buf(:, :)
    integer(hid_t) :: tid
    integer :: stat
    call pack_strings(value, buf)
    call make_string_type(size(buf, 1), tid, stat)
    if (stat < 0) then
      call fail(error, file, 'create string type for dataset', name)
      return
    end if
    ! A dataset of a different string length would mismatch in place: always replace it.
    call delete_link(file, name, error)
    if (.not. allocated(error)) &
      call write_raw(file, name, tid, tid, [integer(hsize_t) :: size(value)], c_loc(buf), error)
    call h5tclose_f(tid, stat)
  end subroutine write_str1

  !> Write a whole dataset (rank 0 dims: scalar). An existing dataset of the same shape is
  !> overwritten in place; one of another shape is replaced. Parent groups are created.
  subroutine write_raw(file, name, memtype, filetype, dims, buf, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: memtype, filetype
    integer(hsize_t), intent(in) :: dims(:)
    type(c_ptr), intent(in) :: buf
    type(error_t), allocatable, intent(out) :: error
    integer(hid_t) :: did, sid
    integer(hsize_t), allocatable :: old(:)
    integer :: stat, ignore
    logical :: same
    if (h5_exists(file, name)) then
      call h5dopen_f(file%id, name, did, stat)
      if (stat < 0) then
        call fail(error, file, 'open dataset', name)
        return
      end if
      call h5dget_space_f(did, sid, stat)
      same = stat >= 0
      if (same) then
        call space_dims(sid, -1, old, stat)
        same = stat >= 0
        if (same) same = size(old) == size(dims)
        if (same) same = all(old == dims)
        call h5sclose_f(sid, ignore)
      end if
      if (same) then
        call clear_os_error()
        call h5dwrite_f(did, memtype, buf, stat)
        if (stat < 0) call fail_io(error, file, 'write dataset', name)
        call close_written(did, file, name, error)
        return
      end if
      call h5dclose_f(did, ignore)
      call delete_link(file, name, error)
      if (allocated(error)) return
    end if
    call make_parent(file, name, error)
    if (allocated(error)) return
    if (size(dims) == 0) then
      call h5screate_f(H5S_SCALAR_F, sid, stat)
    else
      call h5screate_simple_f(size(dims), dims, sid, stat)
    end if
    if (stat < 0) then
      call fail(error, file, 'create dataspace for dataset', name)
      return
    end if
    call clear_os_error()
    call h5dcreate_f(file%id, name, filetype, sid, did, stat)
    if (stat < 0) then
      call fail_io(error, file, 'create dataset', name)
    else
      call h5dwrite_f(did, memtype, buf, stat)
      if (stat < 0) call fail_io(error, file, 'write dataset', name)
      call close_written(did, file, name, error)
    end if
    call h5sclose_f(sid, ignore)
  end subroutine write_raw

  !> Close a dataset just written: the close may write its data (chunk cache) and can fail like
  !> a write; a failure is reported unless an earlier one already is.
  subroutine close_written(did, file, name, error)
    integer(hid_t), intent(in) :: did
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    type(error_t), allocatable, intent(inout) :: error
    integer :: stat
    if (.not. allocated(error)) call clear_os_error()
    call h5dclose_f(did, stat)
    if (stat < 0 .and. .not. allocated(error)) call fail_io(error, file, 'write (close) dataset', name)
  end subroutine close_written

  ! ---------------------------------------------------------------- datasets: whole reads

  subroutine read_r0(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(out) :: value
    type(error_t), allocatable, intent(out) :: error
    real(wp), target :: buf(1)
    integer(hsize_t), allocatable :: dims(:)
    call dataset_dims(file, name, 0, dims, error)
    if (.not. allocated(error)) call read_raw(file, name, H5T_NATIVE_DOUBLE, c_loc(buf), error)
    if (.not. allocated(error)) value = buf(1)
  end subroutine read_r0

  subroutine read_r1(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), allocatable, target, intent(out) :: value(:)
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: d(:)
    call dataset_dims(file, name, 1, d, error)
    if (allocated(error)) return
    allocate (value(d(1)))
    call read_raw(file, name, H5T_NATIVE_DOUBLE, c_loc(value), error)
  end subroutine read_r1

  subroutine read_r2(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), allocatable, target, intent(out) :: value(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: d(:)
    call dataset_dims(file, name, 2, d, error)
    if (allocated(error)) return
    allocate (value(d(1), d(2)))
    call read_raw(file, name, H5T_NATIVE_DOUBLE, c_loc(value), error)
  end subroutine read_r2

  subroutine read_r3(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), allocatable, target, intent(out) :: value(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: d(:)
    call dataset_dims(file, name, 3, d, error)
    if (allocated(error)) return
    allocate (value(d(1), d(2), d(3)))
    call read_raw(file, name, H5T_NATIVE_DOUBLE, c_loc(value), error)
  end subroutine read_r3

  subroutine read_i4_0(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i4), intent(out) :: value
    type(error_t), allocatable, intent(out) :: error
    integer(i4), target :: buf(1)
    integer(hsize_t), allocatable :: dims(:)
    call dataset_dims(file, name, 0, dims, error)
    if (.not. allocated(error)) call read_raw(file, name, h5kind_to_type(int32, H5_INTEGER_KIND), c_loc(buf), error)
    if (.not. allocated(error)) value = buf(1)
  end subroutine read_i4_0

  subroutine read_i4_1(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i4), allocatable, target, intent(out) :: value(:)
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: d(:)
    call dataset_dims(file, name, 1, d, error)
    if (allocated(error)) return
    allocate (value(d(1)))
    call read_raw(file, name, h5kind_to_type(int32, H5_INTEGER_KIND), c_loc(value), error)
  end subroutine read_i4_1

  subroutine read_i4_2(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i4), allocatable, target, intent(out) :: value(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: d(:)
    call dataset_dims(file, name, 2, d, error)
    if (allocated(error)) return
    allocate (value(d(1), d(2)))
    call read_raw(file, name, h5kind_to_type(int32, H5_INTEGER_KIND), c_loc(value), error)
  end subroutine read_i4_2

  subroutine read_i4_3(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i4), allocatable, target, intent(out) :: value(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: d(:)
    call dataset_dims(file, name, 3, d, error)
    if (allocated(error)) return
    allocate (value(d(1), d(2), d(3)))
    call read_raw(file, name, h5kind_to_type(int32, H5_INTEGER_KIND), c_loc(value), error)
  end subroutine read_i4_3

  subroutine read_i8_0(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(out) :: value
    type(error_t), allocatable, intent(out) :: error
    integer(i8), target :: buf(1)
    integer(hsize_t), allocatable :: dims(:)
    call dataset_dims(file, name, 0, dims, error)
    if (.not. allocated(error)) call read_raw(file, name, h5kind_to_type(int64, H5_INTEGER_KIND), c_loc(buf), error)
    if (.not. allocated(error)) value = buf(1)
  end subroutine read_i8_0

  subroutine read_i8_1(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), allocatable, target, intent(out) :: value(:)
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: d(:)
    call dataset_dims(file, name, 1, d, error)
    if (allocated(error)) return
    allocate (value(d(1)))
    call read_raw(file, name, h5kind_to_type(int64, H5_INTEGER_KIND), c_loc(value), error)
  end subroutine read_i8_1

  subroutine read_i8_2(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), allocatable, target, intent(out) :: value(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: d(:)
    call dataset_dims(file, name, 2, d, error)
    if (allocated(error)) return
    allocate (value(d(1), d(2)))
    call read_raw(file, name, h5kind_to_type(int64, H5_INTEGER_KIND), c_loc(value), error)
  end subroutine read_i8_2

  subroutine read_i8_3(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), allocatable, target, intent(out) :: value(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: d(:)
    call dataset_dims(file, name, 3, d, error)
    if (allocated(error)) return
    allocate (value(d(1), d(2), d(3)))
    call read_raw(file, name, h5kind_to_type(int64, H5_INTEGER_KIND), c_loc(value), error)
  end subroutine read_i8_3

  !> Dimensions (Fortran order) of dataset `name`, which must have rank `rank` (0: a scalar
  !> or a one-element dataset; < 0: any rank).
  subroutine dataset_dims(file, name, rank, dims, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(in) :: rank
    integer(hsize_t), allocatable, intent(out) :: dims(:)
    type(error_t), allocatable, intent(out) :: error
    integer(hid_t) :: did, sid
    integer :: stat, ignore
    call open_dataset(file, name, did, error)
    if (allocated(error)) return
    call h5dget_space_f(did, sid, stat)
    if (stat < 0) then
      call fail(error, file, 'get dataspace of dataset', name)
    else
      call space_dims(sid, -1, dims, stat)
      if (stat < 0) then
        call fail(error, file, 'get dimensions of dataset', name)
      else if (rank == 0) then
        if (product(dims) /= 1) call fatal_error(error, "HDF5: dataset '"//name//"' in '"// &
          file%name()//"' is not a scalar")
      else if (rank > 0 .and. size(dims) /= rank) then
        call fatal_error(error, "HDF5: dataset '"//name//"' in '"//file%name()// &
          "' has rank "//to_str(size(dims))//", expected "//to_str(rank))
      end if
      call h5sclose_f(sid, ignore)
    end if
    call h5dclose_f(did, ignore)
  end subroutine dataset_dims

  subroutine read_raw(file, name, memtype, buf, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: memtype
    type(c_ptr), intent(in) :: buf
    type(error_t), allocatable, intent(out) :: error
    integer(hid_t) :: did
    integer :: stat, ignore
    type(c_ptr) :: ptr
    call open_dataset(file, name, did, error)
    if (allocated(error)) return
    call check_numeric(did, file, name, error)
    if (allocated(error)) then
      call h5dclose_f(did, ignore)
      return
    end if
    ptr = buf
    call clear_os_error()
    call h5dread_f(did, memtype, ptr, stat)
    if (stat < 0) then
      call fail_io(error, file, 'read dataset', name)
      error%message = error%message//' (damaged data: checksum mismatch or I/O error)'
    end if
    call h5dclose_f(did, ignore)
  end subroutine read_raw

  !> A dataset read into numbers must hold integers or floating-point numbers (not strings,
  !> compounds, references, ...): the error names the file, the dataset and what it holds.
  subroutine check_numeric(did, file, name, error)
    integer(hid_t), intent(in) :: did
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    type(error_t), allocatable, intent(out) :: error
    integer(hid_t) :: tid
    integer :: stat, tclass, ignore
    call h5dget_type_f(did, tid, stat)
    if (stat < 0) then
      call fail(error, file, 'get the type of dataset', name)
      return
    end if
    call h5tget_class_f(tid, tclass, stat)
    call h5tclose_f(tid, ignore)
    if (stat < 0) then
      call fail(error, file, 'get the type of dataset', name)
    else if (tclass == H5T_STRING_F) then
      call fatal_error(error, "HDF5: dataset '"//name//"' in '"//file%name()//"' holds strings, not numbers")
    else if (tclass /= H5T_FLOAT_F .and. tclass /= H5T_INTEGER_F) then
      call fatal_error(error, "HDF5: dataset '"//name//"' in '"//file%name()//"' does not hold numbers "// &
        '(HDF5 type class '//to_str(tclass)//')')
    end if
  end subroutine check_numeric

  subroutine open_dataset(file, name, did, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hid_t), intent(out) :: did
    type(error_t), allocatable, intent(out) :: error
    integer :: stat
    if (.not. h5_exists(file, name)) then
      call fatal_error(error, "HDF5: dataset '"//name//"' not found in '"//file%name()//"'")
      return
    end if
    call h5dopen_f(file%id, name, did, stat)
    if (stat < 0) call fail(error, file, 'open dataset', name)
  end subroutine open_dataset

  ! ---------------------------------------------------------------- extendible datasets

  !> Create an empty chunked dataset of element kind `kind` (h5_real, h5_int32, h5_int64)
  !> with fixed leading dimensions `inner_dims` (Fortran order, may be empty) and an
  !> unlimited last dimension of current length 0. `chunk` (default 64) entries per chunk.
  subroutine h5_create_extendible(file, name, kind, inner_dims, error, chunk)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(in) :: kind
    integer, intent(in) :: inner_dims(:)
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: chunk
    integer(hsize_t) :: dims(size(inner_dims) + 1), maxdims(size(inner_dims) + 1), &
      chunks(size(inner_dims) + 1)
    integer(hid_t) :: sid, pid, did, ftype
    integer :: stat, ignore, rank
    select case (kind)
    case (h5_real)
      ftype = H5T_IEEE_F64LE
    case (h5_int32)
      ftype = H5T_STD_I32LE
    case (h5_int64)
      ftype = H5T_STD_I64LE
    case default
      call fatal_error(error, "HDF5: unknown element kind for dataset '"//name//"'")
      return
    end select
    rank = size(dims)
    dims(1:rank - 1) = int(inner_dims, hsize_t)
    dims(rank) = 0
    maxdims = dims
    maxdims(rank) = H5S_UNLIMITED_F
    chunks = max(1_hsize_t, dims)
    chunks(rank) = 64
    if (present(chunk)) chunks(rank) = max(1, chunk)
    call make_parent(file, name, error)
    if (allocated(error)) return
    call h5screate_simple_f(rank, dims, sid, stat, maxdims)
    if (stat < 0) then
      call fail(error, file, 'create dataspace for dataset', name)
      return
    end if
    call h5pcreate_f(H5P_DATASET_CREATE_F, pid, stat)
    if (stat >= 0) call h5pset_chunk_f(pid, rank, chunks, stat)
    ! Fletcher-32 checksum per chunk: damage inside the data is detected when it is read.
    if (stat >= 0) call h5pset_fletcher32_f(pid, stat)
    if (stat < 0) then
      call fail(error, file, 'set chunking and checksums for dataset', name)
    else
      call clear_os_error()
      call h5dcreate_f(file%id, name, ftype, sid, did, stat, pid)
      if (stat < 0) then
        call fail_io(error, file, 'create extendible dataset', name)
      else
        call close_written(did, file, name, error)
      end if
    end if
    call h5pclose_f(pid, ignore)
    call h5sclose_f(sid, ignore)
  end subroutine h5_create_extendible

  subroutine append_r0(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value
    type(error_t), allocatable, intent(out) :: error
    real(wp), target :: buf(1)
    buf(1) = value
    call append_raw(file, name, H5T_NATIVE_DOUBLE, [integer(hsize_t) ::], c_loc(buf), error)
  end subroutine append_r0

  subroutine append_r1(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in), target, contiguous :: value(:)
    type(error_t), allocatable, intent(out) :: error
    call append_raw(file, name, H5T_NATIVE_DOUBLE, int(shape(value), hsize_t), c_loc(value), error)
  end subroutine append_r1

  subroutine append_r2(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in), target, contiguous :: value(:, :)
    type(error_t), allocatable, intent(out) :: error
    call append_raw(file, name, H5T_NATIVE_DOUBLE, int(shape(value), hsize_t), c_loc(value), error)
  end subroutine append_r2

  subroutine append_i4_0(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i4), intent(in) :: value
    type(error_t), allocatable, intent(out) :: error
    integer(i4), target :: buf(1)
    buf(1) = value
    call append_raw(file, name, h5kind_to_type(int32, H5_INTEGER_KIND), [integer(hsize_t) ::], c_loc(buf), error)
  end subroutine append_i4_0

  subroutine append_i8_0(file, name, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(in) :: value
    type(error_t), allocatable, intent(out) :: error
    integer(i8), target :: buf(1)
    buf(1) = value
    call append_raw(file, name, h5kind_to_type(int64, H5_INTEGER_KIND), [integer(hsize_t) ::], c_loc(buf), error)
  end subroutine append_i8_0

  !> Grow the last dimension by one and write the slice `inner` (the leading dimensions,
  !> which must match the dataset's) into the new entry.
  subroutine append_raw(file, name, memtype, inner, buf, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: memtype
    integer(hsize_t), intent(in) :: inner(:)
    type(c_ptr), intent(in) :: buf
    type(error_t), allocatable, intent(out) :: error
    integer(hid_t) :: did, fsid, msid
    integer(hsize_t), allocatable :: dims(:)
    integer(hsize_t) :: start(size(inner) + 1), count(size(inner) + 1)
    integer :: stat, ignore, rank
    rank = size(inner) + 1
    call dataset_dims(file, name, rank, dims, error)
    if (allocated(error)) return
    if (any(dims(1:rank - 1) /= inner)) then
      call fatal_error(error, "HDF5: slice appended to dataset '"//name//"' in '"//file%name()// &
        "' does not match its shape")
      return
    end if
    call open_dataset(file, name, did, error)
    if (allocated(error)) return
    dims(rank) = dims(rank) + 1
    call clear_os_error()
    call h5dset_extent_f(did, dims, stat)
    if (stat < 0) then
      call fail_io(error, file, 'extend dataset', name)
      call h5dclose_f(did, ignore)
      return
    end if
    start = 0
    start(rank) = dims(rank) - 1
    count(1:rank - 1) = inner
    count(rank) = 1
    call h5dget_space_f(did, fsid, stat)
    if (stat >= 0) call h5sselect_hyperslab_f(fsid, H5S_SELECT_SET_F, start, count, stat)
    if (stat < 0) then
      call fail(error, file, 'select the new entry of dataset', name)
      call h5dclose_f(did, ignore)
      return
    end if
    call h5screate_simple_f(rank, count, msid, stat)
    if (stat < 0) then
      call fail(error, file, 'create memory dataspace for dataset', name)
    else
      call clear_os_error()
      call h5dwrite_f(did, memtype, buf, stat, msid, fsid)
      if (stat < 0) call fail_io(error, file, 'append to dataset', name)
      call h5sclose_f(msid, ignore)
    end if
    call h5sclose_f(fsid, ignore)
    call close_written(did, file, name, error)
  end subroutine append_raw

  !> Read entry `k` (1-based) along the last dimension of the 3-D real dataset `name`: the 2-D
  !> slice value(n1, n2) (e.g. the positions of one frame) without reading the others.
  subroutine h5_read_entry(file, name, k, value, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(in) :: k
    real(wp), allocatable, target, intent(out) :: value(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: dims(:)
    integer(hsize_t) :: start(3), count(3)
    integer(hid_t) :: did, fsid, msid
    integer :: stat, ignore
    type(c_ptr) :: ptr
    call dataset_dims(file, name, 3, dims, error)
    if (allocated(error)) return
    if (k < 1 .or. k > int(dims(3), i8)) then
      call fatal_error(error, "HDF5: dataset '"//name//"' in '"//file%name()//"' has no entry "//to_str(k))
      return
    end if
    allocate (value(dims(1), dims(2)))
    call open_dataset(file, name, did, error)
    if (allocated(error)) return
    start = [0_hsize_t, 0_hsize_t, int(k - 1, hsize_t)]
    count = [dims(1), dims(2), 1_hsize_t]
    call h5dget_space_f(did, fsid, stat)
    if (stat >= 0) call h5sselect_hyperslab_f(fsid, H5S_SELECT_SET_F, start, count, stat)
    if (stat >= 0) then
      call h5screate_simple_f(3, count, msid, stat)
      if (stat >= 0) then
        call clear_os_error()
        ptr = c_loc(value)
        call h5dread_f(did, H5T_NATIVE_DOUBLE, ptr, stat, msid, fsid)
        call h5sclose_f(msid, ignore)
      end if
      call h5sclose_f(fsid, ignore)
    end if
    if (stat < 0) then
      call fail_io(error, file, 'read entry '//to_str(k)//' of dataset', name)
      error%message = error%message//' (damaged data: checksum mismatch or I/O error)'
    end if
    call h5dclose_f(did, ignore)
  end subroutine h5_read_entry

  !> The end address (EOA) the superblock of the HDF5 file `path` records, and the byte offset
  !> of that field (superblock versions 0-3, 8-byte addresses, no user block); `found` is false
  !> for anything else (not HDF5, other layouts, unreadable). `size` is the file's size.
  subroutine superblock_end(path, size, eoa, at, version, found)
    character(len=*), intent(in) :: path
    integer(i8), intent(out) :: size, eoa
    integer, intent(out) :: at, version
    logical, intent(out) :: found
    character(len=1) :: head(48)
    character(len=8), parameter :: signature = char(137)//'HDF'//achar(13)//achar(10)//achar(26)//achar(10)
    integer :: unit, ios, k
    found = .false.
    eoa = 0
    at = 0
    version = -1
    inquire (file=path, size=size)
    if (size < 48) return
    open (newunit=unit, file=path, access='stream', form='unformatted', status='old', action='read', iostat=ios)
    if (ios /= 0) return
    read (unit, iostat=ios) head
    close (unit)
    if (ios /= 0) return
    do k = 1, 8
      if (head(k) /= signature(k:k)) return
    end do
    version = iachar(head(9))
    select case (version)
    case (0)
      if (iachar(head(14)) /= 8) return
      at = 40
    case (1)
      if (iachar(head(14)) /= 8) return
      at = 44
    case (2, 3)
      if (iachar(head(10)) /= 8) return
      at = 28
    case default
      return
    end select
    do k = 8, 1, -1
      eoa = eoa*256 + iachar(head(at + k))
    end do
    found = .true.
  end subroutine superblock_end

  !> A file cut short by a write that failed (full disk, file size limit) after HDF5 had
  !> recorded its new end in the superblock cannot be opened ("truncated file"). Extend such a
  !> file with zeros to the end address its superblock records (superblock versions 0-3, 8-byte
  !> addresses, no user block), so that what was written before can be read and checked.
  !> `extended` tells whether the file was such a file; `old_size` and `new_size` its sizes.
  subroutine h5_extend_truncated(path, extended, old_size, new_size, error)
    character(len=*), intent(in) :: path
    logical, intent(out) :: extended
    integer(i8), intent(out) :: old_size, new_size
    type(error_t), allocatable, intent(out) :: error
    integer :: unit, ios, at, version
    logical :: found
    extended = .false.
    call superblock_end(path, old_size, new_size, at, version, found)
    if (.not. found) then
      new_size = 0
      return
    end if
    if (new_size <= old_size .or. new_size > 1024_i8*old_size + 2_i8**30) return
    open (newunit=unit, file=path, access='stream', form='unformatted', status='old', action='readwrite', &
          iostat=ios)
    if (ios == 0) write (unit, pos=new_size, iostat=ios) achar(0)
    if (ios == 0) close (unit, iostat=ios)
    if (ios /= 0) then
      call fatal_error(error, "cannot extend the truncated file '"//path//"' to "//to_str(new_size)//' bytes')
      return
    end if
    extended = .true.
  end subroutine h5_extend_truncated

  !> The opposite case: a process killed while HDF5 flushed the file may have written new
  !> objects (a new chunk of an extendible dataset, new metadata) at its end and the references
  !> to them, but not yet the superblock with the new end address. HDF5 then sees them beyond
  !> the end of the file's address space, fails on them and would allocate that space again.
  !> Raise the recorded end to the file's size (superblock versions 0 and 1, which carry no
  !> checksum; later versions are left alone). `raised` tells whether the file was such a file;
  !> `old_end` and `new_end` are the recorded end before and after.
  subroutine h5_raise_end(path, raised, old_end, new_end, error)
    character(len=*), intent(in) :: path
    logical, intent(out) :: raised
    integer(i8), intent(out) :: old_end, new_end
    type(error_t), allocatable, intent(out) :: error
    integer :: unit, ios, at, version, k
    logical :: found
    character(len=1) :: bytes(8)
    raised = .false.
    call superblock_end(path, new_end, old_end, at, version, found)
    if (.not. found .or. version > 1 .or. new_end <= old_end) then
      new_end = old_end
      return
    end if
    do k = 1, 8
      bytes(k) = achar(int(mod(shiftr(new_end, 8*(k - 1)), 256_i8)))
    end do
    open (newunit=unit, file=path, access='stream', form='unformatted', status='old', action='readwrite', &
          iostat=ios)
    if (ios == 0) write (unit, pos=at + 1, iostat=ios) bytes
    if (ios == 0) close (unit, iostat=ios)
    if (ios /= 0) then
      call fatal_error(error, "cannot record the end of '"//path//"' in its superblock")
      return
    end if
    raised = .true.
  end subroutine h5_raise_end

  !> Set the length of the last (extendible) dimension to `length`: truncates (the entries
  !> beyond are dropped) or extends (new entries hold the fill value 0).
  subroutine h5_set_length(file, name, length, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(in) :: length
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: dims(:)
    integer(hid_t) :: did
    integer :: stat
    call dataset_dims(file, name, -1, dims, error)
    if (allocated(error)) return
    if (length < 0) then
      call fatal_error(error, "HDF5: negative length requested for dataset '"//name//"'")
      return
    end if
    call open_dataset(file, name, did, error)
    if (allocated(error)) return
    dims(size(dims)) = int(length, hsize_t)
    call clear_os_error()
    call h5dset_extent_f(did, dims, stat)
    if (stat < 0) call fail_io(error, file, 'set the extent of dataset', name)
    call close_written(did, file, name, error)
  end subroutine h5_set_length

  !> Current length of the last (extendible) dimension of dataset `name`.
  subroutine h5_length(file, name, length, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(out) :: length
    type(error_t), allocatable, intent(out) :: error
    integer(hsize_t), allocatable :: dims(:)
    length = 0
    call dataset_dims(file, name, -1, dims, error)
    if (allocated(error)) return
    if (size(dims) == 0) then
      call fatal_error(error, "HDF5: dataset '"//name//"' in '"//file%name()//"' is a scalar")
      return
    end if
    length = int(dims(size(dims)), i8)
  end subroutine h5_length

  ! ---------------------------------------------------------------- helpers

  !> Error "HDF5: cannot <what> '<obj>' in file '<path>'".
  subroutine fail(error, file, what, obj)
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: what, obj
    call fatal_error(error, "HDF5: cannot "//what//" '"//obj//"' in file '"//file%name()//"'")
  end subroutine fail

  !> `fail` for a write, flush or close: adds the operating system's reason when there is one
  !> (': No space left on device', ': File too large').
  subroutine fail_io(error, file, what, obj)
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: what, obj
    call fatal_error(error, "HDF5: cannot "//what//" '"//obj//"' in file '"//file%name()//"'"//os_reason())
  end subroutine fail_io

  !> ': <strerror(errno)>' after a failed system call, else ''.
  function os_reason() result(text)
    character(len=:), allocatable :: text
    text = os_error_text()
    if (len(text) > 0) text = ': '//text
  end function os_reason

  !> Dimensions of a dataspace in Fortran order. rank >= 0 requires that rank (stat = -1
  !> otherwise); rank < 0 accepts any. A scalar dataspace has zero dimensions.
  subroutine space_dims(sid, rank, dims, stat)
    integer(hid_t), intent(in) :: sid
    integer, intent(in) :: rank
    integer(hsize_t), allocatable, intent(out) :: dims(:)
    integer, intent(out) :: stat
    integer :: ndims
    integer(hsize_t), allocatable :: maxdims(:)
    call h5sget_simple_extent_ndims_f(sid, ndims, stat)
    if (stat < 0) return
    allocate (dims(ndims), maxdims(ndims))
    if (ndims > 0) then
      call h5sget_simple_extent_dims_f(sid, dims, maxdims, stat)
      if (stat /= ndims) then   ! returns the rank on success, -1 on failure
        stat = -1
        return
      end if
    end if
    stat = 0
    if (rank >= 0 .and. ndims /= rank) stat = -1
  end subroutine space_dims

  !> Fixed-length, null-padded string type of `n` bytes.
  subroutine make_string_type(n, tid, stat)
    integer, intent(in) :: n
    integer(hid_t), intent(out) :: tid
    integer, intent(out) :: stat
    call h5tcopy_f(H5T_FORTRAN_S1, tid, stat)
    if (stat < 0) return
    call h5tset_size_f(tid, int(n, size_t), stat)
    if (stat < 0) return
    call h5tset_strpad_f(tid, H5T_STR_NULLPAD_F, stat)
  end subroutine make_string_type

  !> Strings as a (maxlen, n) array of bytes, trailing blanks trimmed and null-padded.
  subroutine pack_strings(value, buf)
    character(len=*), intent(in) :: value(:)
    character(kind=c_char), allocatable, intent(out) :: buf(:, :)
    integer :: i, k, n
    n = 1
    do i = 1, size(value)
      n = max(n, len_trim(value(i)))
    end do
    allocate (buf(n, size(value)))
    buf = c_null_char
    do i = 1, size(value)
      do k = 1, len_trim(value(i))
        buf(k, i) = value(i)(k:k)
      end do
    end do
  end subroutine pack_strings

  pure function c_null() result(p)
    use, intrinsic :: iso_c_binding, only: c_null_ptr
    type(c_ptr) :: p
    p = c_null_ptr
  end function c_null

  !> Delete the object (group with everything below it, or dataset) `name`; a missing
  !> object is not an error. The file space is not reclaimed (HDF5 limitation).
  subroutine h5_delete(file, name, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    type(error_t), allocatable, intent(out) :: error
    call delete_link(file, name, error)
  end subroutine h5_delete

  !> Rename the link `from` to `to` (same file; the object itself is kept as it is: nothing is
  !> read or freed, so this also works for an object whose own structure is damaged).
  subroutine h5_move(file, from, to, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: from, to
    type(error_t), allocatable, intent(out) :: error
    integer :: stat
    call clear_os_error()
    call h5lmove_f(file%id, from, file%id, to, stat)
    if (stat < 0) call fail_io(error, file, 'rename to '//to//' the object', from)
  end subroutine h5_move

  !> Delete link `name` if it exists.
  subroutine delete_link(file, name, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    type(error_t), allocatable, intent(out) :: error
    integer :: stat
    if (.not. h5_exists(file, name)) return
    call h5ldelete_f(file%id, name, stat)
    if (stat < 0) call fail(error, file, 'delete', name)
  end subroutine delete_link

  !> Create the groups above `name` ('/a/b/c' creates '/a/b').
  subroutine make_parent(file, name, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    type(error_t), allocatable, intent(out) :: error
    integer :: k
    k = index(name, '/', back=.true.)
    if (k > 1) call h5_create_group(file, name(1:k - 1), error)
  end subroutine make_parent

end module kf_h5
