# tactus_embed(<target> <function> FILES <file>...): compiles the files' bytes into <target> as
#   std::vector<tactus::EmbeddedFile> <function>()   (name: the file's name, text: its bytes)
# so an executable carries its assets (the interactive report's page, script and vendored
# library) and needs no install path to find them. The generated source is rebuilt when a file
# changes.
function(tactus_embed target function)
  cmake_parse_arguments(E "" "" "FILES" ${ARGN})
  set(out ${CMAKE_CURRENT_BINARY_DIR}/${function}.cpp)
  add_custom_command(OUTPUT ${out}
    COMMAND ${CMAKE_COMMAND} -DOUT=${out} -DFUNCTION=${function} "-DFILES=${E_FILES}"
            -P ${PROJECT_SOURCE_DIR}/cmake/TactusEmbedWrite.cmake
    DEPENDS ${E_FILES} ${PROJECT_SOURCE_DIR}/cmake/TactusEmbedWrite.cmake
    COMMENT "Embedding ${function}: ${E_FILES}" VERBATIM)
  target_sources(${target} PRIVATE ${out})
endfunction()
