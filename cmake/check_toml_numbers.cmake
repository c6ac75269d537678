# Checks that no non-test source reads a TOML number with toml++'s value<double>() or
# value_or<double>(): an integer beyond 2^53 gives nothing there, and a read that dereferenced
# it took garbage. Every number goes through number_of() in experiments/io/toml_reader.cpp, the
# one file allowed to name them.
# Inputs: -DROOT=<source tree> -DDIRS="a;b;..." (folders under ROOT to read).
cmake_minimum_required(VERSION 3.20)
set(_bad "")
foreach(_dir IN LISTS DIRS)
  file(GLOB_RECURSE _files ${ROOT}/${_dir}/*.cpp ${ROOT}/${_dir}/*.hpp ${ROOT}/${_dir}/*.h
       ${ROOT}/${_dir}/*.cc)
  foreach(_f IN LISTS _files)
    file(RELATIVE_PATH _rel ${ROOT} ${_f})
    if(_rel STREQUAL "experiments/io/toml_reader.cpp")
      continue()
    endif()
    file(STRINGS ${_f} _reads REGEX "\\.value(_or)?[ \t]*<[ \t]*(double|float)[ \t]*>[ \t]*\\(")
    foreach(_r IN LISTS _reads)
      string(STRIP "${_r}" _r)
      string(APPEND _bad "\n  ${_rel}: ${_r}")
    endforeach()
  endforeach()
endforeach()
if(_bad)
  message(FATAL_ERROR "a TOML number read with value<double>(), which gives nothing for an "
                      "integer beyond 2^53; read it with number_of() "
                      "(experiments/io/toml_reader.hpp):${_bad}")
endif()
message(STATUS "toml number check passed")
