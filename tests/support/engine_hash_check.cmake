# Checks cmake/write_version.cmake's source hashes on a scratch tree: an edit of the loop's logic
# leaves the engine and imaging hashes alone, an edit of sim/ changes the engine's only, one of
# render/ the imaging's only, and another compiler changes both. Prints "engine hash check
# passed" or fails with the step that did not hold.
# Inputs: -DSCRIPT=<cmake/write_version.cmake> -DWORK=<scratch folder>
file(REMOVE_RECURSE ${WORK})
foreach(f sim/world.cpp render/renderer.cpp experiments/loop/loop.cpp experiments/pile/run.cpp)
  file(WRITE ${WORK}/src/${f} "// ${f}\n")
endforeach()
file(WRITE ${WORK}/template.in "@REPOSETWIN_ENGINE_HASH@ @REPOSETWIN_IMAGING_HASH@")

function(hashes out compiler)
  execute_process(COMMAND ${CMAKE_COMMAND} -DSOURCE_DIR=${WORK}/src -DPROJECT_VERSION=0
                          -DTEMPLATE=${WORK}/template.in -DOUT=${WORK}/out.txt
                          "-DCOMPILER=${compiler}" "-DBUILD_FLAGS=Release -O2"
                          -P ${SCRIPT}
                  RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "write_version.cmake failed (${rc})")
  endif()
  file(READ ${WORK}/out.txt text)
  set(${out} ${text} PARENT_SCOPE)
endfunction()

# Fails unless hash `old` -> `new` (of `kind`) changed as `want_same` says.
function(check what kind old new want_same)
  if(want_same AND NOT old STREQUAL new)
    message(FATAL_ERROR "${what}: the ${kind} hash changed (${old} -> ${new})")
  elseif(NOT want_same AND old STREQUAL new)
    message(FATAL_ERROR "${what}: the ${kind} hash did not change (${old})")
  endif()
endfunction()

function(expect what got want_engine_same want_imaging_same)
  string(REPLACE " " ";" a "${before}")
  string(REPLACE " " ";" b "${got}")
  list(GET a 0 e0)
  list(GET a 1 i0)
  list(GET b 0 e1)
  list(GET b 1 i1)
  string(LENGTH "${e1}" n)
  if(NOT n EQUAL 16)
    message(FATAL_ERROR "${what}: the engine hash '${e1}' is not 16 hex digits")
  endif()
  check("${what}" engine "${e0}" "${e1}" ${want_engine_same})
  check("${what}" imaging "${i0}" "${i1}" ${want_imaging_same})
endfunction()

hashes(before "GNU 12.2.0")
file(APPEND ${WORK}/src/experiments/loop/loop.cpp "int changed_logic;\n")
hashes(got "GNU 12.2.0")
expect("an edit of the loop's logic" "${got}" TRUE TRUE)
file(APPEND ${WORK}/src/sim/world.cpp "int changed_physics;\n")
hashes(got "GNU 12.2.0")
expect("an edit of sim/" "${got}" FALSE TRUE)
set(before "${got}")
file(APPEND ${WORK}/src/render/renderer.cpp "int changed_look;\n")
hashes(got "GNU 12.2.0")
expect("an edit of render/" "${got}" TRUE FALSE)
set(before "${got}")
file(WRITE ${WORK}/src/experiments/pile/new_file.cpp "// new\n")
hashes(got "GNU 12.2.0")
expect("a new file in experiments/pile/" "${got}" FALSE TRUE)
set(before "${got}")
hashes(got "Clang 16.0.0")
expect("another compiler" "${got}" FALSE FALSE)
message(STATUS "engine hash check passed")
