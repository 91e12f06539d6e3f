# SPDX-License-Identifier: MIT
# citymesh_module(NAME SOURCES... [DEPS ...] [PRIVATE_DEPS ...]) makes the static library
# citymesh_NAME with the project's warnings, sanitizers and public include folder.
function(citymesh_apply_flags target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
    -Wno-sign-conversion -Wnon-virtual-dtor -Wold-style-cast -Woverloaded-virtual)
  if(CITYMESH_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

if(CITYMESH_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=address,undefined)
endif()

function(citymesh_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(citymesh_${name} STATIC ${ARG_SOURCES})
  add_library(citymesh::${name} ALIAS citymesh_${name})
  target_include_directories(citymesh_${name} PUBLIC "${PROJECT_SOURCE_DIR}/include"
    PRIVATE "${CMAKE_CURRENT_SOURCE_DIR}")
  target_link_libraries(citymesh_${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  citymesh_apply_flags(citymesh_${name})
endfunction()
