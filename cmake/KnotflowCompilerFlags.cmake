# Fortran flags chosen by compiler id: GNU (gfortran), IntelLLVM / Intel (ifx, ifort), LLVMFlang /
# Flang (flang-new). Sets CMAKE_Fortran_FLAGS (appended to what the user gave), and the
# Release and Debug flags; the build information (kf_build_info) records what was used.
#
# Debug builds check every array bound and trap invalid operations, divisions by zero and
# overflows (the Debug unit-test run of scripts/test.sh relies on that); Release builds
# optimise for the machine class, not the build host, so a binary runs on every node of a
# cluster.

set(_kf_base "")
set(_kf_release "-O3")
set(_kf_debug "-O0 -g")
if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64|amd64)$")
  set(_kf_x86 ON)
else()
  set(_kf_x86 OFF)
endif()

if(CMAKE_Fortran_COMPILER_ID STREQUAL "GNU")
  # -Wall -Wextra, with three warnings off:
  #  -Wno-compare-reals: the code compares reals for equality on purpose (an exact zero as
  #    "not set" or "no flow", a value against the one it was copied from or read back); each
  #    such test is exact by construction, and -Wextra flags every one of them (46 warnings before).
  #  -Wno-unused-dummy-argument: implementations of a deferred binding (a model, a stepper,
  #    a step monitor, a task worker) take the interface's full argument list and use only
  #    part of it (31 warnings before).
  #  -Wno-maybe-uninitialized: with optimisation, gfortran 12 reports the hidden length of a
  #    deferred-length character variable (`.line`) at its first assignment `line = ...`,
  #    which reads it only when the variable is already allocated (5 warnings, none real; the
  #    two real ones this warning found, results of the benchmarks left undefined on an early
  #    error return, are fixed). Debug builds (-O0) do not run this analysis anyway.
  set(_kf_base "-std=f2008 -ffree-line-length-none -fimplicit-none -Wall -Wextra -Wno-compare-reals -Wno-unused-dummy-argument -Wno-maybe-uninitialized")
  set(_kf_release "-O3 -funroll-loops")
  if(_kf_x86)
    string(APPEND _kf_release " -march=x86-64-v2")
  endif()
  set(_kf_debug "-O0 -g -fcheck=all -ffpe-trap=invalid,zero,overflow -finit-real=snan -fbacktrace")
elseif(CMAKE_Fortran_COMPILER_ID MATCHES "^(IntelLLVM|Intel)$")
  set(_kf_base "-stand f08 -warn all -diag-disable=5268")   # 5268: lines beyond column 132
  set(_kf_release "-O3")
  if(_kf_x86)
    string(APPEND _kf_release " -march=x86-64-v2")
  endif()
  set(_kf_debug "-O0 -g -check all -fpe0 -init=snan -traceback")
elseif(CMAKE_Fortran_COMPILER_ID MATCHES "^(LLVMFlang|Flang)$")
  set(_kf_base "-fimplicit-none")
  set(_kf_release "-O3")
  set(_kf_debug "-O0 -g")
else()
  message(WARNING "knotflow: no flags known for the Fortran compiler ${CMAKE_Fortran_COMPILER_ID}; "
                  "using CMake's defaults")
  set(_kf_release "${CMAKE_Fortran_FLAGS_RELEASE}")
  set(_kf_debug "${CMAKE_Fortran_FLAGS_DEBUG}")
endif()

string(APPEND CMAKE_Fortran_FLAGS " ${_kf_base}")
string(STRIP "${CMAKE_Fortran_FLAGS}" CMAKE_Fortran_FLAGS)
set(CMAKE_Fortran_FLAGS_RELEASE "${_kf_release}")
set(CMAKE_Fortran_FLAGS_DEBUG "${_kf_debug}")
