# LinuxCNC HAL modules (LinuxCNC 2.9, uspace). TRUECUT_LINUXCNC:
#   AUTO (default): build them when LinuxCNC's development headers are found,
#                   otherwise say so and skip;
#   ON:  the headers are required;
#   OFF: never.
# The modules are built into ${TRUECUT_LINUXCNC_MODULE_BUILD_DIR};
# `cmake --install <build> --component linuxcnc` copies them to
# TRUECUT_LINUXCNC_MODULE_DIR, where LinuxCNC's `loadrt` looks for modules.
set(TRUECUT_LINUXCNC AUTO CACHE STRING "Build the LinuxCNC HAL module (AUTO, ON, OFF)")
set_property(CACHE TRUECUT_LINUXCNC PROPERTY STRINGS AUTO ON OFF)
set(TRUECUT_LINUXCNC_MODULE_DIR /usr/lib/linuxcnc/modules
    CACHE PATH "LinuxCNC's module folder (where `cmake --install --component linuxcnc` puts the modules)")
set(TRUECUT_LINUXCNC_MODULE_BUILD_DIR ${CMAKE_BINARY_DIR}/linuxcnc)

set(TRUECUT_HAVE_LINUXCNC OFF)
if(TRUECUT_LINUXCNC STREQUAL "OFF")
  message(STATUS "LinuxCNC HAL module: off (TRUECUT_LINUXCNC=OFF)")
else()
  find_path(LINUXCNC_INCLUDE_DIR NAMES hal.h rtapi_app.h PATH_SUFFIXES linuxcnc
            DOC "LinuxCNC's HAL/RTAPI headers (Debian: linuxcnc-uspace-dev)")
  if(TRUECUT_SANITIZE)
    set(why "not with TRUECUT_SANITIZE (rtapi_app cannot load a sanitized module)")
  elseif(NOT LINUXCNC_INCLUDE_DIR)
    set(why "LinuxCNC's hal.h not found (Debian: apt-get install linuxcnc-uspace-dev)")
  else()
    set(TRUECUT_HAVE_LINUXCNC ON)
  endif()
  if(TRUECUT_HAVE_LINUXCNC)
    message(STATUS "LinuxCNC HAL module: building (headers in ${LINUXCNC_INCLUDE_DIR})")
  elseif(TRUECUT_LINUXCNC STREQUAL "ON")
    message(FATAL_ERROR "TRUECUT_LINUXCNC=ON: ${why}")
  else()
    message(STATUS "LinuxCNC HAL module: skipped, ${why}")
  endif()
endif()

# The flags halcompile gives a uspace module (Makefile.modinc: RTFLAGS and
# EXTRA_CFLAGS), for the sources that include LinuxCNC's headers.
set(TRUECUT_LINUXCNC_FLAGS -DRTAPI -D_GNU_SOURCE -Drealtime -DUSPACE -D__MODULE__ -DSIM
    -fno-fast-math -fno-unsafe-math-optimizations -fno-builtin-sin -fno-builtin-cos
    -fno-builtin-sincos)
if(CMAKE_SYSTEM_PROCESSOR MATCHES "x86_64|i.86")
  list(APPEND TRUECUT_LINUXCNC_FLAGS -mieee-fp)
endif()

# truecut_linuxcnc_module(<target> MODULE <name> LINUXCNC_SOURCES... [SOURCES...] [DEPS...]
#                         [OUTPUT_DIR dir] [NO_INSTALL])
# A LinuxCNC module `<name>.so`: LINUXCNC_SOURCES include LinuxCNC's headers
# and get its flags; SOURCES and DEPS are compiled as in the rest of the tree.
# NO_INSTALL: a module for tests, never installed.
# Only rtapi_app's entry points and module parameters are exported (the
# version script; LinuxCNC's macros do not mark them visible).
function(truecut_linuxcnc_module target)
  cmake_parse_arguments(M "NO_INSTALL" "MODULE;OUTPUT_DIR" "LINUXCNC_SOURCES;SOURCES;DEPS" ${ARGN})
  if(NOT M_OUTPUT_DIR)
    set(M_OUTPUT_DIR ${TRUECUT_LINUXCNC_MODULE_BUILD_DIR})
  endif()
  add_library(${target} MODULE ${M_LINUXCNC_SOURCES} ${M_SOURCES})
  set_source_files_properties(${M_LINUXCNC_SOURCES} TARGET_DIRECTORY ${target} PROPERTIES
                              COMPILE_OPTIONS "${TRUECUT_LINUXCNC_FLAGS}")
  target_include_directories(${target} SYSTEM PRIVATE ${LINUXCNC_INCLUDE_DIR})
  target_compile_definitions(${target} PRIVATE TRUECUT_LINUXCNC_MODULE="${M_MODULE}")
  target_link_libraries(${target} PRIVATE ${M_DEPS} Threads::Threads -Wl,--exclude-libs,ALL
                        -Wl,-Bsymbolic
                        -Wl,--version-script=${PROJECT_SOURCE_DIR}/rt/linuxcnc/module.ver)
  set_target_properties(${target} PROPERTIES PREFIX "" OUTPUT_NAME ${M_MODULE}
                        LIBRARY_OUTPUT_DIRECTORY ${M_OUTPUT_DIR}
                        LINK_DEPENDS ${PROJECT_SOURCE_DIR}/rt/linuxcnc/module.ver)
  if(NOT M_NO_INSTALL)
    install(TARGETS ${target} LIBRARY DESTINATION ${TRUECUT_LINUXCNC_MODULE_DIR}
            COMPONENT linuxcnc EXCLUDE_FROM_ALL)
  endif()
endfunction()
