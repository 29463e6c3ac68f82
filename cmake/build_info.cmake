# Runs at every build (not just configure) so `sirl version` names the commit actually built.
# Inputs: SRC_DIR, IN, OUT, VERSION, BUILD_TYPE, COMPILER, FLAGS.
execute_process(COMMAND git rev-parse --short=12 HEAD WORKING_DIRECTORY ${SRC_DIR}
                OUTPUT_VARIABLE SIRL_GIT_COMMIT OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
execute_process(COMMAND git status --porcelain --untracked-files=no WORKING_DIRECTORY ${SRC_DIR}
                OUTPUT_VARIABLE dirty OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT SIRL_GIT_COMMIT)
  set(SIRL_GIT_COMMIT "unknown")
elseif(dirty)
  set(SIRL_GIT_COMMIT "${SIRL_GIT_COMMIT}-dirty")
endif()
set(PROJECT_VERSION ${VERSION})
set(CMAKE_BUILD_TYPE ${BUILD_TYPE})
set(SIRL_CXX_COMPILER ${COMPILER})
set(SIRL_CXX_FLAGS ${FLAGS})
configure_file(${IN} ${OUT}.tmp @ONLY)
file(COPY_FILE ${OUT}.tmp ${OUT} ONLY_IF_DIFFERENT)
