# Checks that no non-test source starts a program through a shell or by hand: no call of
# std::system, system, popen, wordexp or the exec family. Every program starts through
# experiments/io/process.hpp (an argument vector, posix_spawnp, never a shell).
# Inputs: -DROOT=<source tree> -DDIRS="a;b;..." (folders under ROOT to read).
cmake_minimum_required(VERSION 3.20)
set(_bad "")
foreach(_dir IN LISTS DIRS)
  file(GLOB_RECURSE _files ${ROOT}/${_dir}/*.cpp ${ROOT}/${_dir}/*.hpp ${ROOT}/${_dir}/*.h
       ${ROOT}/${_dir}/*.cc ${ROOT}/${_dir}/*.in)
  foreach(_f IN LISTS _files)
    # A call: the name, then its opening parenthesis (a comment naming std::system is fine).
    file(STRINGS ${_f} _calls REGEX
         "(^|[^A-Za-z0-9_])(system|popen|execv|execvp|execve|execvpe|execl|execlp|execle|fexecve|wordexp)[ \t]*\\(")
    foreach(_c IN LISTS _calls)
      file(RELATIVE_PATH _rel ${ROOT} ${_f})
      string(STRIP "${_c}" _c)
      string(APPEND _bad "\n  ${_rel}: ${_c}")
    endforeach()
  endforeach()
endforeach()
if(_bad)
  message(FATAL_ERROR "a program started through a shell or exec by hand; start it with "
                      "experiments/io/process.hpp (run_program) instead:${_bad}")
endif()
message(STATUS "no shell check passed")
