# libFuzzer targets (tests/fuzz), included by tests/CMakeLists.txt.
#
# libFuzzer ships with clang while the main build uses g++, so the targets are
# a small project of their own (tests/fuzz/CMakeLists.txt) that this builds
# with clang++ as part of the normal build. MESHLIGHT_FUZZ: AUTO builds them
# when clang++ can link a libFuzzer target and warns loudly when it cannot;
# ON makes that an error; OFF skips them.
set(MESHLIGHT_FUZZ AUTO CACHE STRING "Build and run the libFuzzer targets: AUTO, ON or OFF")
set_property(CACHE MESHLIGHT_FUZZ PROPERTY STRINGS AUTO ON OFF)
# Wall-clock seconds the ctest `fuzz_obj_loader` fuzzes for (the run also
# reads the corpus first, a second or two). CI's share: a regression run
# over the corpus and a little past it, its three fuzzers together about a
# minute of the test run's twenty; fuzz longer as tests/fuzz/README.md says.
set(MESHLIGHT_FUZZ_SECONDS 25 CACHE STRING "Seconds each fuzz test runs its fuzzer")
# The photometric loaders are small and fast (about 15000 inputs a second):
# a shorter run of `fuzz_photometric` reaches them.
set(MESHLIGHT_FUZZ_PHOTOMETRIC_SECONDS 10 CACHE STRING "Seconds the ctest fuzz_photometric runs its fuzzer")
# The glTF loader runs about 1000 inputs a second under the sanitizers
# (tinygltf's JSON parsing dominates): 15 s reach past the corpus's seeds,
# which cover every accessor and material path.
set(MESHLIGHT_FUZZ_GLTF_SECONDS 15 CACHE STRING "Seconds the ctest fuzz_gltf_loader runs its fuzzer")

if(MESHLIGHT_FUZZ STREQUAL "OFF")
  return()
endif()

find_program(MESHLIGHT_FUZZ_CXX NAMES clang++-14 clang++ DOC "clang++ for the libFuzzer targets")

# Can it link a fuzz target with the sanitizers? (Debian: clang ships the
# compiler, libclang-rt-14-dev the libFuzzer and sanitizer runtimes.) Checked
# once per compiler; a failure is checked again on the next configure.
set(_fuzz_ok FALSE)
set(_fuzz_why "clang++ was not found (Debian: apt-get install clang libclang-rt-14-dev)")
if(MESHLIGHT_FUZZ_CXX)
  if(MESHLIGHT_FUZZ_CHECKED STREQUAL MESHLIGHT_FUZZ_CXX)
    set(_fuzz_ok TRUE)
  else()
    set(_dir ${CMAKE_CURRENT_BINARY_DIR}/fuzz-check)
    file(MAKE_DIRECTORY ${_dir})
    file(WRITE ${_dir}/check.cpp
         "#include <cstddef>\n#include <cstdint>\n"
         "extern \"C\" int LLVMFuzzerTestOneInput(const uint8_t*, size_t) { return 0; }\n")
    execute_process(COMMAND ${MESHLIGHT_FUZZ_CXX} -fsanitize=fuzzer,address,undefined check.cpp -o check
                    WORKING_DIRECTORY ${_dir} RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
    if(_rc EQUAL 0)
      set(_fuzz_ok TRUE)
      set(MESHLIGHT_FUZZ_CHECKED ${MESHLIGHT_FUZZ_CXX} CACHE INTERNAL "clang++ that linked a fuzz target")
    else()
      string(STRIP "${_out}" _out)
      set(_fuzz_why "${MESHLIGHT_FUZZ_CXX} cannot link a libFuzzer target with ASan and UBSan "
                    "(Debian: apt-get install libclang-rt-14-dev):\n${_out}")
    endif()
  endif()
endif()

if(NOT _fuzz_ok)
  if(MESHLIGHT_FUZZ STREQUAL "ON")
    message(FATAL_ERROR "MESHLIGHT_FUZZ=ON but ${_fuzz_why}")
  endif()
  message(WARNING "\n*** The loader fuzzers (ctest fuzz_obj_loader, fuzz_photometric, fuzz_gltf_loader) are NOT built and NOT run: ${_fuzz_why}\n"
                  "*** Install them (.ci/install-deps does) or configure with -DMESHLIGHT_FUZZ=OFF.\n")
  return()
endif()
message(STATUS "Fuzz targets: built with ${MESHLIGHT_FUZZ_CXX}")

include(ExternalProject)
# BUILD_ALWAYS: the sub-build checks its own dependencies (the loader's
# sources), so edits to them rebuild the fuzzer.
ExternalProject_Add(meshlight_fuzz_targets
  SOURCE_DIR ${CMAKE_CURRENT_SOURCE_DIR}/fuzz
  BINARY_DIR ${CMAKE_CURRENT_BINARY_DIR}/fuzz
  CMAKE_ARGS -DCMAKE_CXX_COMPILER=${MESHLIGHT_FUZZ_CXX} -DCMAKE_BUILD_TYPE=
  INSTALL_COMMAND ""
  BUILD_ALWAYS ON)

# A bounded run on a copy of the committed corpus (libFuzzer adds to the
# corpus it is given); fails on any crash, sanitizer report, leak or hang.
add_test(NAME fuzz_obj_loader
         COMMAND ${CMAKE_COMMAND}
                 -DFUZZER=${CMAKE_CURRENT_BINARY_DIR}/fuzz/fuzz_obj_loader
                 -DCORPUS=${CMAKE_CURRENT_SOURCE_DIR}/fuzz/corpus
                 -DDICT=${CMAKE_CURRENT_SOURCE_DIR}/fuzz/obj.dict
                 -DWORK=${CMAKE_CURRENT_BINARY_DIR}/fuzz-run/obj_loader
                 -DSECONDS=${MESHLIGHT_FUZZ_SECONDS}
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/fuzz/RunFuzzer.cmake)
set_tests_properties(fuzz_obj_loader PROPERTIES LABELS fuzz TIMEOUT 300)

add_test(NAME fuzz_photometric
         COMMAND ${CMAKE_COMMAND}
                 -DFUZZER=${CMAKE_CURRENT_BINARY_DIR}/fuzz/fuzz_photometric
                 -DCORPUS=${CMAKE_CURRENT_SOURCE_DIR}/fuzz/corpus_photometric
                 -DDICT=${CMAKE_CURRENT_SOURCE_DIR}/fuzz/photometric.dict
                 -DWORK=${CMAKE_CURRENT_BINARY_DIR}/fuzz-run/photometric
                 -DSECONDS=${MESHLIGHT_FUZZ_PHOTOMETRIC_SECONDS}
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/fuzz/RunFuzzer.cmake)
set_tests_properties(fuzz_photometric PROPERTIES LABELS fuzz TIMEOUT 300)

add_test(NAME fuzz_gltf_loader
         COMMAND ${CMAKE_COMMAND}
                 -DFUZZER=${CMAKE_CURRENT_BINARY_DIR}/fuzz/fuzz_gltf_loader
                 -DCORPUS=${CMAKE_CURRENT_SOURCE_DIR}/fuzz/corpus_gltf
                 -DDICT=${CMAKE_CURRENT_SOURCE_DIR}/fuzz/gltf.dict
                 -DWORK=${CMAKE_CURRENT_BINARY_DIR}/fuzz-run/gltf_loader
                 -DSECONDS=${MESHLIGHT_FUZZ_GLTF_SECONDS}
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/fuzz/RunFuzzer.cmake)
set_tests_properties(fuzz_gltf_loader PROPERTIES LABELS fuzz TIMEOUT 300)
