# Writes the code version (PROJECT_VERSION + git describe) into one generated .cpp at build time.
# configure_file rewrites OUT only when the text changes, so a new commit recompiles one file and
# relinks, instead of every target that saw a compile definition.
# Inputs: -DSOURCE_DIR=<repo> -DPROJECT_VERSION=<x.y.z> -DTEMPLATE=<version.cpp.in> -DOUT=<file>
execute_process(COMMAND git describe --always --dirty --tags
                WORKING_DIRECTORY ${SOURCE_DIR}
                OUTPUT_VARIABLE REPOSETWIN_GIT_VERSION
                OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT REPOSETWIN_GIT_VERSION)
  set(REPOSETWIN_GIT_VERSION "unknown")
endif()
set(REPOSETWIN_VERSION_STRING "${PROJECT_VERSION}+${REPOSETWIN_GIT_VERSION}")
configure_file(${TEMPLATE} ${OUT} @ONLY)
