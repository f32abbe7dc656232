# One static library per module; the link graph is the dependency graph of DESIGN.md.
set(CM_WARNINGS -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wno-unknown-pragmas)

function(cm_module name)
  cmake_parse_arguments(M "" "" "SOURCES;DEPS" ${ARGN})
  add_library(curvemesh_${name} STATIC ${M_SOURCES})
  add_library(curvemesh::${name} ALIAS curvemesh_${name})
  target_include_directories(curvemesh_${name} PUBLIC ${PROJECT_SOURCE_DIR}/src)
  target_compile_options(curvemesh_${name} PRIVATE ${CM_WARNINGS})
  target_link_libraries(curvemesh_${name} PUBLIC ${M_DEPS})
  set_target_properties(curvemesh_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
endfunction()
