# truecut_module(<name> [DEPS targets...] [PRIVATE_DEPS targets...])
# One library target per module folder: public headers in include/, sources and
# internal headers in src/. Sources are globbed so that adding a file needs no
# edit here.
function(truecut_module name)
  cmake_parse_arguments(M "" "" "DEPS;PRIVATE_DEPS" ${ARGN})
  file(GLOB_RECURSE srcs CONFIGURE_DEPENDS
       ${CMAKE_CURRENT_SOURCE_DIR}/src/*.cpp ${CMAKE_CURRENT_SOURCE_DIR}/src/*.c)
  if(srcs)
    add_library(truecut_${name} STATIC ${srcs})
    target_include_directories(truecut_${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include
                                               PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src)
    target_link_libraries(truecut_${name} PUBLIC ${M_DEPS} PRIVATE ${M_PRIVATE_DEPS})
    set_target_properties(truecut_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  else()
    add_library(truecut_${name} INTERFACE)
    if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/include)
      target_include_directories(truecut_${name} INTERFACE ${CMAKE_CURRENT_SOURCE_DIR}/include)
    endif()
    target_link_libraries(truecut_${name} INTERFACE ${M_DEPS})
  endif()
  add_library(truecut::${name} ALIAS truecut_${name})
endfunction()

# truecut_component(<name> SOURCES...) builds a HAL component as a shared
# library that `loadrt <name>` finds in the build's component folder.
function(truecut_component name)
  cmake_parse_arguments(C "" "" "SOURCES;DEPS" ${ARGN})
  add_library(${name} MODULE ${C_SOURCES})
  set_target_properties(${name} PROPERTIES PREFIX "" LIBRARY_OUTPUT_DIRECTORY
                                           ${TRUECUT_COMPONENT_DIR} C_VISIBILITY_PRESET hidden
                                           CXX_VISIBILITY_PRESET hidden)
  target_link_libraries(${name} PRIVATE truecut_hal_abi ${C_DEPS})
  install(TARGETS ${name} LIBRARY DESTINATION lib/truecut/components)
  set_property(GLOBAL APPEND PROPERTY TRUECUT_COMPONENTS ${name})
endfunction()
