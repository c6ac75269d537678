# Writes the code version (PROJECT_VERSION + git describe) into one generated .cpp at build time,
# with two content hashes of the sources that make a result: the engine's (what a pile run's
# result depends on) and the imaging's (what a photograph of a pile and its measurement depend
# on). Result caches are keyed by these, not by the commit: a commit that changes neither (the
# loop's logic, a report, a document) finds the piles and photographs made before it, and one
# that changes either makes them afresh. Each hash covers the compiler and flags too (the same
# sources built otherwise may round otherwise), every file under the listed folders (an edit not
# yet committed included), and errs towards re-making.
# configure_file rewrites OUT only when the text changes, so a new commit recompiles one file and
# relinks, instead of every target that saw a compile definition.
# Inputs: -DSOURCE_DIR=<repo> -DPROJECT_VERSION=<x.y.z> -DTEMPLATE=<version.cpp.in> -DOUT=<file>
#         -DCOMPILER=<id and version> -DBUILD_FLAGS=<build type and flags>
execute_process(COMMAND git describe --always --dirty --tags
                WORKING_DIRECTORY ${SOURCE_DIR}
                OUTPUT_VARIABLE REPOSETWIN_GIT_VERSION
                OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT REPOSETWIN_GIT_VERSION)
  set(REPOSETWIN_GIT_VERSION "unknown")
endif()
set(REPOSETWIN_VERSION_STRING "${PROJECT_VERSION}+${REPOSETWIN_GIT_VERSION}")

# SHA-256 over the compiler, the flags and every file (path and content) under the paths given
# (folders or files, relative to SOURCE_DIR), in sorted order; its first 16 hex digits.
function(sources_hash out)
  set(files)
  foreach(p IN LISTS ARGN)
    if(IS_DIRECTORY ${SOURCE_DIR}/${p})
      file(GLOB_RECURSE found RELATIVE ${SOURCE_DIR} ${SOURCE_DIR}/${p}/*)
      list(APPEND files ${found})
    else()
      list(APPEND files ${p})
    endif()
  endforeach()
  list(SORT files)
  set(text "${COMPILER}\n${BUILD_FLAGS}\n")
  foreach(f IN LISTS files)
    if(EXISTS ${SOURCE_DIR}/${f})
      file(SHA256 ${SOURCE_DIR}/${f} h)
    else()
      set(h missing)
    endif()
    string(APPEND text "${f} ${h}\n")
  endforeach()
  string(SHA256 all "${text}")
  string(SUBSTRING ${all} 0 16 short)
  set(${out} ${short} PARENT_SCOPE)
endfunction()

# The engine: the DEM, the pile test around it, the scene and its inputs, the run folders, the
# loop's pile requests (loop_sim); the build files (flags). The imaging: the camera, renderer and vision, the photo pipeline and the
# loop's photograph settings (loop_sim). Both use numeric/ (the median).
sources_hash(REPOSETWIN_ENGINE_HASH sim numeric experiments/pile experiments/io experiments/campaign
             experiments/loop/loop_sim.cpp experiments/loop/loop_sim.hpp CMakeLists.txt cmake
             experiments/CMakeLists.txt)
sources_hash(REPOSETWIN_IMAGING_HASH camera numeric render vision experiments/photos
             experiments/loop/loop_sim.cpp experiments/loop/loop_sim.hpp)
configure_file(${TEMPLATE} ${OUT} @ONLY)
