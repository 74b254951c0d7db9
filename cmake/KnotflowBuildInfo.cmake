# Writes kf_build_info.f90 from its template with the commit the sources are at (run at configure
# time and again before every build, so a binary never carries the commit of an older configure).
# -DSOURCE_DIR -DTEMPLATE -DOUTPUT -DPROJECT_VERSION -DKNOTFLOW_COMPILER -DKNOTFLOW_FLAGS
# The commit gets the suffix -dirty when tracked files differ from it. configure_file rewrites
# the output only when its text changes, so an unchanged commit recompiles nothing.
execute_process(COMMAND git rev-parse --short=12 HEAD
                WORKING_DIRECTORY ${SOURCE_DIR}
                OUTPUT_VARIABLE KNOTFLOW_GIT_HASH OUTPUT_STRIP_TRAILING_WHITESPACE
                ERROR_QUIET RESULT_VARIABLE _git_rc)
if(NOT _git_rc EQUAL 0 OR KNOTFLOW_GIT_HASH STREQUAL "")
  set(KNOTFLOW_GIT_HASH "unknown")
else()
  execute_process(COMMAND git diff --quiet HEAD --
                  WORKING_DIRECTORY ${SOURCE_DIR} ERROR_QUIET RESULT_VARIABLE _dirty)
  if(_dirty EQUAL 1)
    string(APPEND KNOTFLOW_GIT_HASH "-dirty")
  endif()
endif()
configure_file(${TEMPLATE} ${OUTPUT} @ONLY)
