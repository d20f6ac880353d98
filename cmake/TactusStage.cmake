# tactus_add_stage(<stage> SOURCES src... [PUBLIC deps...] [PRIVATE deps...] [EXECUTABLES exe main.cpp ...])
# A stage library tactus::<stage> (headers in include/, installed and exported) with its thin
# executables, each linked to the library and the shared CLI convention.
function(tactus_add_stage stage)
  cmake_parse_arguments(S "" "" "SOURCES;PUBLIC;PRIVATE;EXECUTABLES" ${ARGN})
  set(lib tactus_${stage})
  add_library(${lib} STATIC ${S_SOURCES})
  add_library(tactus::${stage} ALIAS ${lib})
  set_target_properties(${lib} PROPERTIES EXPORT_NAME ${stage} OUTPUT_NAME ${lib})
  target_include_directories(${lib} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${lib} PUBLIC tactus::core ${S_PUBLIC} PRIVATE ${S_PRIVATE})
  tactus_target_defaults(${lib})
  install(TARGETS ${lib} EXPORT tactusTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(DIRECTORY include/tactus DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.hpp")
  while(S_EXECUTABLES)
    list(POP_FRONT S_EXECUTABLES exe main)
    add_executable(${exe} ${main})
    target_link_libraries(${exe} PRIVATE ${lib} tactus_cli)
    tactus_target_defaults(${exe})
    install(TARGETS ${exe} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endwhile()
endfunction()
