# Writes a ctest file that runs a GoogleTest binary one suite per process, run after each build
# of the binary (tests/CMakeLists.txt, reposetwin_gtest_suites).
#
# Why not gtest_discover_tests: it adds one ctest test, so one process, per gtest test. A test
# binary that links OpenCV, OSMesa and VTK loads about 160 shared libraries, and relocating them
# costs about 0.27 s of CPU per process (perf: ld.so and the kernel's page faults), which is
# 0.27 s × 490 processes, about a third of the unit label's CPU time. CMake's GoogleTest module
# has no per-suite mode, so this script lists the tests itself.
#
# Each suite is one ctest test named <prefix><Suite>, labelled `unit`, running every test of the
# suite that the E2E gtest filter does not match. Each test the filter matches is its own ctest test
# <prefix><Suite>.<Test>, labelled `e2e`: those are long, and one process each lets ctest run two
# at once. A single test is still run alone with the binary's --gtest_filter.
#
# Inputs (-D): BINARY, PREFIX, E2E (a gtest filter, ':'-separated), ENVIRONMENT (VAR=value pairs,
# ','-separated), TIMEOUT_UNIT, TIMEOUT_E2E, CTEST_FILE.

string(REPLACE "," ";" ENVIRONMENT "${ENVIRONMENT}")
execute_process(COMMAND ${CMAKE_COMMAND} -E env ${ENVIRONMENT} "${BINARY}" --gtest_list_tests
                OUTPUT_VARIABLE listing RESULT_VARIABLE rc ERROR_VARIABLE err TIMEOUT 60)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "listing the tests of ${BINARY} failed (exit ${rc}): ${err}")
endif()

# The E2E patterns are exact names or Suite.* forms; glob them to regexes once.
string(REPLACE ":" ";" e2e_patterns "${E2E}")
set(e2e_regexes)
foreach(p IN LISTS e2e_patterns)
  string(REPLACE "." "\\." r "${p}")
  string(REPLACE "*" ".*" r "${r}")
  list(APPEND e2e_regexes "^${r}$")
endforeach()

function(is_e2e name out)
  foreach(r IN LISTS e2e_regexes)
    if(name MATCHES "${r}")
      set(${out} TRUE PARENT_SCOPE)
      return()
    endif()
  endforeach()
  set(${out} FALSE PARENT_SCOPE)
endfunction()

# gtest's listing: a suite line "Suite." (or "Prefix/Suite.  # TypeParam = ..."), then its tests
# indented by two spaces ("  Test" or "  Test/3  # GetParam() = ...").
string(REPLACE ";" "\\;" listing "${listing}")
string(REPLACE "\n" ";" lines "${listing}")
set(suites)
set(suite "")
foreach(line IN LISTS lines)
  string(REGEX REPLACE " *#.*$" "" line "${line}")
  if(line MATCHES "^  ([^ ]+)$")
    set(full "${suite}.${CMAKE_MATCH_1}")
    is_e2e("${full}" e2e)
    if(e2e)
      list(APPEND e2e_tests "${full}")
    else()
      list(APPEND unit_in_${suite} "${full}")
    endif()
  elseif(line MATCHES "^([^ ]+)\\.$")
    set(suite "${CMAKE_MATCH_1}")
    list(APPEND suites "${suite}")
  endif()
endforeach()

set(script "")
macro(add_one name filter label timeout)
  string(APPEND script "add_test([==[${PREFIX}${name}]==] [==[${BINARY}]==] "
                       "[==[--gtest_filter=${filter}]==])\n")
  string(APPEND script "set_tests_properties([==[${PREFIX}${name}]==] PROPERTIES "
                       "LABELS ${label} TIMEOUT ${timeout} ENVIRONMENT [==[${ENVIRONMENT}]==])\n")
endmacro()

foreach(s IN LISTS suites)
  if(unit_in_${s})
    if(E2E)
      add_one("${s}" "${s}.*:-${E2E}" unit ${TIMEOUT_UNIT})
    else()
      add_one("${s}" "${s}.*" unit ${TIMEOUT_UNIT})
    endif()
  endif()
endforeach()
foreach(t IN LISTS e2e_tests)
  add_one("${t}" "${t}" e2e ${TIMEOUT_E2E})
endforeach()

file(WRITE "${CTEST_FILE}.tmp" "${script}")
file(RENAME "${CTEST_FILE}.tmp" "${CTEST_FILE}")
