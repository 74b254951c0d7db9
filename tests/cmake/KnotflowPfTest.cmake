# knotflow_add_pf_test(NAME <name> SOURCES <files.pf> [LIBS <targets>] [MPI_PES <n>]
#                      [LABELS <labels>] [WORKING_DIRECTORY <dir>])
#
# Builds one test executable from pFUnit 4 .pf files and registers it as ONE ctest entry.
#   SOURCES  .pf files, relative to the calling CMakeLists.txt (or absolute paths in the
#            source tree); each must hold `module <file base name>`.
#   LIBS     targets to link (default: knotflow_lib).
#   MPI_PES  run under MPI with that many processes (tests use @mpitest(npes=[...]));
#            the test is skipped (not registered) when KNOTFLOW_WITH_MPI is OFF.
#   LABELS   extra ctest labels; `slow` keeps a test out of the default test command.
# Every test also gets the label `unit` (serial) or `mpi` (MPI_PES given).
#
# With a real pFUnit (find_package(PFUNIT 4) succeeded in tests/CMakeLists.txt) this calls
# pFUnit's add_pfunit_ctest(); otherwise it uses the project's fallback runner in
# tests/pfunit_fallback (funitproc.py + modules funit/pfunit).
#
# Variables read from tests/CMakeLists.txt: KNOTFLOW_PFUNIT_REAL, KNOTFLOW_PYTHON3,
# KNOTFLOW_FUNITPROC, KNOTFLOW_MPIEXEC_FLAGS.

function(knotflow_add_pf_test)
  cmake_parse_arguments(PARSE_ARGV 0 KPF "" "NAME;MPI_PES;WORKING_DIRECTORY" "SOURCES;LIBS;LABELS")
  if(KPF_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "knotflow_add_pf_test: unknown arguments: ${KPF_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT KPF_NAME)
    message(FATAL_ERROR "knotflow_add_pf_test: NAME is required")
  endif()
  if(NOT KPF_SOURCES)
    message(FATAL_ERROR "knotflow_add_pf_test(${KPF_NAME}): SOURCES is required")
  endif()
  if(NOT KPF_LIBS)
    set(KPF_LIBS knotflow_lib)
  endif()
  if(NOT KPF_WORKING_DIRECTORY)
    set(KPF_WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
  endif()
  foreach(pf IN LISTS KPF_SOURCES)
    if(NOT pf MATCHES "\\.pf$")
      message(FATAL_ERROR "knotflow_add_pf_test(${KPF_NAME}): ${pf} is not a .pf file")
    endif()
  endforeach()

  if(KPF_MPI_PES)
    if(NOT KPF_MPI_PES MATCHES "^[1-9][0-9]*$")
      message(FATAL_ERROR "knotflow_add_pf_test(${KPF_NAME}): MPI_PES must be a positive integer")
    endif()
    if(NOT KNOTFLOW_WITH_MPI)
      message(STATUS "knotflow_add_pf_test: ${KPF_NAME} skipped (KNOTFLOW_WITH_MPI is OFF)")
      return()
    endif()
    set(kind mpi)
  else()
    set(kind unit)
  endif()

  if(KNOTFLOW_PFUNIT_REAL)
    _knotflow_add_real_pfunit_test()
  else()
    _knotflow_add_fallback_pf_test()
  endif()

  set_tests_properties(${KPF_NAME} PROPERTIES LABELS "${kind};${KPF_LABELS}" TIMEOUT 600)
  if(KPF_MPI_PES)
    set_tests_properties(${KPF_NAME} PROPERTIES PROCESSORS ${KPF_MPI_PES})
  endif()
  add_dependencies(knotflow_tests ${KPF_NAME})
  if(kind STREQUAL "unit")
    add_dependencies(knotflow_unit_tests ${KPF_NAME})
  endif()
endfunction()

# Real pFUnit 4: one add_pfunit_ctest() per call (it creates target and test ${KPF_NAME}).
# Runs in the scope of knotflow_add_pf_test (a macro), so the variables set here only
# shadow MPIEXEC / MPIEXEC_PREFLAGS inside that function call.
macro(_knotflow_add_real_pfunit_test)
  # pFUnit's add_pfunit_ctest reads MPIEXEC (not MPIEXEC_EXECUTABLE) and MPIEXEC_PREFLAGS.
  set(MPIEXEC ${MPIEXEC_EXECUTABLE})
  set(MPIEXEC_PREFLAGS ${MPIEXEC_PREFLAGS} ${KNOTFLOW_MPIEXEC_FLAGS})
  if(KPF_MPI_PES)
    add_pfunit_ctest(${KPF_NAME}
      TEST_SOURCES ${KPF_SOURCES}
      LINK_LIBRARIES ${KPF_LIBS}
      MAX_PES ${KPF_MPI_PES}
      WORKING_DIRECTORY ${KPF_WORKING_DIRECTORY})
  else()
    add_pfunit_ctest(${KPF_NAME}
      TEST_SOURCES ${KPF_SOURCES}
      LINK_LIBRARIES ${KPF_LIBS}
      WORKING_DIRECTORY ${KPF_WORKING_DIRECTORY})
  endif()
  # pFUnit's generated sources are not guaranteed to be Fortran 2008: lift the project's
  # -std=f2008 for these targets only (later -std options win); all other flags stay.
  target_compile_options(${KPF_NAME} PRIVATE $<$<COMPILE_LANG_AND_ID:Fortran,GNU>:-std=gnu>)
endmacro()

# Fallback: preprocess each .pf with funitproc.py, generate a driver, link funit_fallback.
macro(_knotflow_add_fallback_pf_test)
  set(_gen_dir ${CMAKE_CURRENT_BINARY_DIR}/${KPF_NAME}.gen)
  set(_pf_abs "")
  set(_gen_srcs "")
  foreach(pf IN LISTS KPF_SOURCES)
    get_filename_component(_abs ${pf} ABSOLUTE BASE_DIR ${CMAKE_CURRENT_SOURCE_DIR})
    if(NOT EXISTS ${_abs})
      message(FATAL_ERROR "knotflow_add_pf_test(${KPF_NAME}): ${_abs} does not exist")
    endif()
    get_filename_component(_base ${pf} NAME_WE)
    set(_out ${_gen_dir}/${_base}.F90)
    add_custom_command(OUTPUT ${_out}
      COMMAND ${KNOTFLOW_PYTHON3} ${KNOTFLOW_FUNITPROC} preprocess ${_abs} ${_out}
      DEPENDS ${_abs} ${KNOTFLOW_FUNITPROC}
      COMMENT "funit: preprocessing ${_base}.pf"
      VERBATIM)
    list(APPEND _pf_abs ${_abs})
    list(APPEND _gen_srcs ${_out})
  endforeach()

  set(_driver ${_gen_dir}/${KPF_NAME}_driver.F90)
  set(_mpi_flag "")
  if(KPF_MPI_PES)
    set(_mpi_flag --mpi --np ${KPF_MPI_PES})
  endif()
  add_custom_command(OUTPUT ${_driver}
    COMMAND ${KNOTFLOW_PYTHON3} ${KNOTFLOW_FUNITPROC} driver ${_mpi_flag} --name ${KPF_NAME}
            -o ${_driver} ${_pf_abs}
    DEPENDS ${_pf_abs} ${KNOTFLOW_FUNITPROC}
    COMMENT "funit: generating the driver of ${KPF_NAME}"
    VERBATIM)

  add_executable(${KPF_NAME} ${_gen_srcs} ${_driver})
  # Own module directory: test modules of different executables never collide.
  set_target_properties(${KPF_NAME} PROPERTIES Fortran_MODULE_DIRECTORY ${_gen_dir}/mod)
  target_include_directories(${KPF_NAME} PRIVATE ${_gen_dir}/mod)
  target_link_libraries(${KPF_NAME} PRIVATE ${KPF_LIBS} funit_fallback)

  if(KPF_MPI_PES)
    target_link_libraries(${KPF_NAME} PRIVATE pfunit_fallback)
    add_test(NAME ${KPF_NAME}
      COMMAND ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} ${KPF_MPI_PES}
              ${KNOTFLOW_MPIEXEC_FLAGS} ${MPIEXEC_PREFLAGS} $<TARGET_FILE:${KPF_NAME}>
              ${MPIEXEC_POSTFLAGS}
      WORKING_DIRECTORY ${KPF_WORKING_DIRECTORY})
  else()
    add_test(NAME ${KPF_NAME} COMMAND $<TARGET_FILE:${KPF_NAME}>
      WORKING_DIRECTORY ${KPF_WORKING_DIRECTORY})
  endif()
endmacro()
