# meshlight_embed_shaders(TARGET NAMESPACE ns FILES a.vert b.frag ...)
# Generates a C++ source holding each file as a string constant, named after
# the file with '.' replaced by '_' (gather_fisheye.vert -> gather_fisheye_vert),
# so nothing depends on the working directory at run time (Filament's approach).
function(meshlight_embed_shaders target)
  cmake_parse_arguments(ARG "" "NAMESPACE" "FILES" ${ARGN})
  set(out_cpp "${CMAKE_CURRENT_BINARY_DIR}/${target}_shaders.cpp")
  set(out_h "${CMAKE_CURRENT_BINARY_DIR}/${target}_shaders.h")
  set(abs_files "")
  foreach(f ${ARG_FILES})
    list(APPEND abs_files "${CMAKE_CURRENT_SOURCE_DIR}/${f}")
  endforeach()
  # A list would be split into separate arguments: pass it joined by '|'.
  string(REPLACE ";" "|" files_arg "${abs_files}")
  add_custom_command(
    OUTPUT "${out_cpp}" "${out_h}"
    COMMAND ${CMAKE_COMMAND} -DOUT_CPP=${out_cpp} -DOUT_H=${out_h}
            -DNAMESPACE=${ARG_NAMESPACE} "-DFILES=${files_arg}"
            -P "${PROJECT_SOURCE_DIR}/cmake/EmbedShadersScript.cmake"
    DEPENDS ${abs_files} "${PROJECT_SOURCE_DIR}/cmake/EmbedShadersScript.cmake"
    COMMENT "Embedding shaders for ${target}"
    VERBATIM)
  target_sources(${target} PRIVATE "${out_cpp}" "${out_h}")
  target_include_directories(${target} PUBLIC "${CMAKE_CURRENT_BINARY_DIR}")
endfunction()
