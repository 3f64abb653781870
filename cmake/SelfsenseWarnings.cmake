# Warning and sanitizer flags shared by every selfsense target.
add_library(selfsense_build_flags INTERFACE)
add_library(selfsense::build_flags ALIAS selfsense_build_flags)
target_compile_options(selfsense_build_flags INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wsign-conversion -Wold-style-cast
  -Wnon-virtual-dtor -Woverloaded-virtual -Wdouble-promotion
  $<$<BOOL:${SELFSENSE_WERROR}>:-Werror>)
if(SELFSENSE_SANITIZE)
  target_compile_options(selfsense_build_flags INTERFACE
    -fsanitize=${SELFSENSE_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  target_link_options(selfsense_build_flags INTERFACE -fsanitize=${SELFSENSE_SANITIZE})
endif()

# Registers a target for installation in the selfsense export set.
function(selfsense_export target)
  set_property(GLOBAL APPEND PROPERTY SELFSENSE_EXPORTED_TARGETS ${target})
endfunction()
