# calstand_embed_files(OUT_CPP <file> NAMESPACE <ns> FUNCTION <fn> FILES <f>...)
#
# Generates a C++ source defining
#   std::optional<std::string_view> <ns>::<fn>(std::string_view file_name);
#   std::vector<std::string_view> <ns>::<fn>_names();
# that return the text of each listed file by its base name, so that schemas and shipped data
# files have one source of truth in the repository and still work from an installed binary.
# The generated file is rebuilt whenever a listed file changes.
function(calstand_embed_files)
  cmake_parse_arguments(ARG "" "OUT_CPP;NAMESPACE;FUNCTION" "FILES" ${ARGN})
  set(script "${CMAKE_CURRENT_FUNCTION_LIST_DIR}/CalstandEmbedGenerate.cmake")
  # A '|'-joined list survives the trip through the command line; the script splits it again.
  string(REPLACE ";" "|" files_arg "${ARG_FILES}")
  add_custom_command(
    OUTPUT "${ARG_OUT_CPP}"
    COMMAND ${CMAKE_COMMAND} "-DOUT=${ARG_OUT_CPP}" "-DNS=${ARG_NAMESPACE}"
            "-DFN=${ARG_FUNCTION}" "-DFILES=${files_arg}" -P "${script}"
    DEPENDS ${ARG_FILES} "${script}"
    COMMENT "Embedding ${ARG_FUNCTION} files"
    VERBATIM)
endfunction()
