# Project-wide compile settings applied per target (no global flags).
add_library(haptic_compile_options INTERFACE)
add_library(haptic::compile_options ALIAS haptic_compile_options)
target_compile_options(haptic_compile_options INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor>)
if(HAPTIC_ENABLE_ASAN)
  # Not vptr: gRPC's libraries are built without RTTI, so UBSan cannot check the dynamic type of
  # the objects they make, and reports their shared_ptr control blocks as having "invalid vptr".
  target_compile_options(haptic_compile_options INTERFACE -fsanitize=address,undefined
                         -fno-sanitize=vptr -fno-omit-frame-pointer)
  target_link_options(haptic_compile_options INTERFACE -fsanitize=address,undefined -fno-sanitize=vptr)
endif()

# haptic_apply_options(<target>): private warnings and sanitizer flags for one of our targets.
function(haptic_apply_options target)
  target_link_libraries(${target} PRIVATE $<BUILD_INTERFACE:haptic::compile_options>)
endfunction()
