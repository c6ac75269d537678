# Checks cmake/gtest_suites.cmake on a fake test binary (fake_tests.sh): every unit suite is one
# ctest test that runs it without its e2e tests, every e2e test is its own ctest test, a suite
# with only e2e tests has no unit entry, and parametrised and typed suites keep their names.
# Prints "gtest suites check passed" or fails naming the line that was wanted.
# Inputs: -DSCRIPT=<cmake/gtest_suites.cmake> -DFAKE=<fake_tests.sh> -DOUT=<ctest file to write>
execute_process(COMMAND ${CMAKE_COMMAND} -DBINARY=${FAKE} -DPREFIX=m.
                        "-DE2E=Loop.*:Mixed.Slow" -DENVIRONMENT=A=1,B=2
                        -DTIMEOUT_UNIT=30 -DTIMEOUT_E2E=90 -DCTEST_FILE=${OUT} -P ${SCRIPT}
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "gtest_suites.cmake failed (${rc})")
endif()
file(READ ${OUT} text)

function(want line)
  string(FIND "${text}" "${line}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "missing from the ctest file: ${line}\n--- the file:\n${text}")
  endif()
endfunction()
function(refuse piece)
  string(FIND "${text}" "${piece}" at)
  if(NOT at EQUAL -1)
    message(FATAL_ERROR "should not be in the ctest file: ${piece}\n--- the file:\n${text}")
  endif()
endfunction()

want("add_test([==[m.Plain]==] [==[${FAKE}]==] [==[--gtest_filter=Plain.*:-Loop.*:Mixed.Slow]==])")
want("add_test([==[m.Mixed]==] [==[${FAKE}]==] [==[--gtest_filter=Mixed.*:-Loop.*:Mixed.Slow]==])")
want("add_test([==[m.Angles/Cone]==] [==[${FAKE}]==] [==[--gtest_filter=Angles/Cone.*:-Loop.*:Mixed.Slow]==])")
want("add_test([==[m.Typed/0]==]")
want("add_test([==[m.Loop.LongA]==] [==[${FAKE}]==] [==[--gtest_filter=Loop.LongA]==])")
want("add_test([==[m.Loop.LongB]==]")
want("add_test([==[m.Mixed.Slow]==] [==[${FAKE}]==] [==[--gtest_filter=Mixed.Slow]==])")
want("set_tests_properties([==[m.Plain]==] PROPERTIES LABELS unit TIMEOUT 30 ENVIRONMENT [==[A=1;B=2]==])")
want("set_tests_properties([==[m.Mixed.Slow]==] PROPERTIES LABELS e2e TIMEOUT 90")
refuse("add_test([==[m.Loop]==]")
refuse("m.Plain.One")
string(REGEX MATCHALL "add_test\\(" adds "${text}")
list(LENGTH adds n)
if(NOT n EQUAL 7)
  message(FATAL_ERROR "wanted 7 ctest tests (4 unit suites, 3 e2e tests), got ${n}:\n${text}")
endif()
message("gtest suites check passed")
