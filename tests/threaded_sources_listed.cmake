# ctest threaded_sources_listed: every GoogleTest case that scripts/tsan.sh runs under
# ThreadSanitizer (a name matching THREADED_REGEX) is in a file of THREADED_SOURCES, the files the
# tsan preset builds sirl_tests from. Otherwise that case would silently not run under TSan.
#   cmake -DLISTS=<build>/threaded-tests.cmake -DDIR=<source>/tests -P threaded_sources_listed.cmake
cmake_minimum_required(VERSION 3.25)  # IN_LIST and the other policies of the build
include(${LISTS})
set(checked 0)
set(missing "")
foreach(f IN LISTS TEST_SOURCES)
  file(STRINGS ${DIR}/${f} cases REGEX "^TEST(_F)?\\([A-Za-z0-9_]+, *[A-Za-z0-9_]+\\)")
  foreach(c IN LISTS cases)
    string(REGEX REPLACE "^TEST(_F)?\\(([A-Za-z0-9_]+), *([A-Za-z0-9_]+)\\).*" "\\2.\\3" c "${c}")
    if(c MATCHES "${THREADED_REGEX}")
      math(EXPR checked "${checked} + 1")
      if(NOT f IN_LIST THREADED_SOURCES)
        list(APPEND missing "tests/${f}: ${c}")
      endif()
    endif()
  endforeach()
endforeach()
if(missing)
  list(JOIN missing "\n  " missing)
  message(FATAL_ERROR "cases ThreadSanitizer runs (scripts/tsan.sh) in files the tsan build "
                      "leaves out; add the files to SIRL_THREADED_TEST_SOURCES "
                      "(tests/CMakeLists.txt):\n  ${missing}")
endif()
if(checked EQUAL 0)
  message(FATAL_ERROR "no case matches ${THREADED_REGEX}: the pattern or the parsing is wrong")
endif()
message(STATUS "${checked} threaded cases, all in the files the tsan build compiles")
