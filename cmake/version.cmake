# Writes the build's identity header from cmake/version.h.in with the source
# tree's `git describe` as it is now. Run at configure time and again by the
# tb_version target on every build: a revision read only at configure time
# goes stale after the next commit, and provenance (image metadata,
# `testbed version`) would name the wrong one. configure_file leaves the
# header untouched when its text is unchanged, so nothing recompiles then.
# Inputs: SRC (source tree), OUT (header), VERSION (project version),
# GIT (git executable, may be empty).
set(TB_GIT_REVISION "unknown")
if(GIT AND EXISTS "${SRC}/.git")
  execute_process(COMMAND "${GIT}" describe --always --dirty --abbrev=12
                  WORKING_DIRECTORY "${SRC}"
                  OUTPUT_VARIABLE rev OUTPUT_STRIP_TRAILING_WHITESPACE
                  RESULT_VARIABLE rc ERROR_QUIET)
  if(rc EQUAL 0 AND rev)
    set(TB_GIT_REVISION "${rev}")
  endif()
endif()
set(PROJECT_VERSION "${VERSION}")
configure_file("${SRC}/cmake/version.h.in" "${OUT}" @ONLY)
