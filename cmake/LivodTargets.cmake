# Shared compile settings and helpers for livod targets.

add_library(livod_warnings INTERFACE)
target_compile_options(livod_warnings INTERFACE
  -Wall -Wextra -Wshadow -Wnon-virtual-dtor -Wcast-align -Woverloaded-virtual
  -Wimplicit-fallthrough
  # GCC 12 warns on designated initializers that omit defaulted members, which is exactly how
  # plain config structs are meant to be used.
  -Wno-missing-field-initializers)
if(LIVOD_WERROR)
  target_compile_options(livod_warnings INTERFACE -Werror)
endif()

if(LIVOD_BUILD_FUZZ)
  # Coverage instrumentation for every library; the fuzz targets add the libFuzzer main.
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer -g)
  add_link_options(-fsanitize=address,undefined)
elseif(LIVOD_SANITIZE)
  # -g1: line tables, all a sanitizer report's stack needs (function, file, line); full debug
  # information made each compile 10-20 % slower, and CI compiles the libraries twice with it.
  add_compile_options(-fsanitize=${LIVOD_SANITIZE} -fno-omit-frame-pointer -g1)
  add_link_options(-fsanitize=${LIVOD_SANITIZE})
  if(LIVOD_SANITIZE MATCHES "undefined")
    add_compile_options(-fno-sanitize-recover=undefined)
  endif()
endif()

# Precompiled header of the tests (LIVOD_PCH, cmake/pch/test_pch.hpp): GoogleTest, Eigen and the
# standard headers most tests parse; it saves 15 % of the tests' compile time. Built once by a
# small owner target with the flags of the tests that reuse it: GCC rejects a precompiled header
# built with other code-generation flags (-fPIE for executables, not a library's -fPIC) or with
# other macros it depends on (-pthread defines _REENTRANT, so every test compiles with -pthread).
# CMake adds -Winvalid-pch, an error under -Werror: a mismatch cannot pass unnoticed. (The
# libraries do without: their compiles are mostly optimisation, a header gained them under 10 %.)
# Call livod_add_pch_owner() once the packages are found.
function(livod_add_pch_owner)
  if(NOT LIVOD_PCH OR NOT LIVOD_BUILD_TESTS)
    return()
  endif()
  add_executable(livod_test_pch ${PROJECT_SOURCE_DIR}/cmake/pch/pch_anchor.cpp)
  target_compile_options(livod_test_pch PRIVATE -pthread)
  target_link_libraries(livod_test_pch PRIVATE livod_warnings Eigen3::Eigen GTest::gtest
                                               GTest::gtest_main)
  target_precompile_headers(livod_test_pch PRIVATE ${PROJECT_SOURCE_DIR}/cmake/pch/test_pch.hpp)
endfunction()

# livod_reuse_test_pch(TARGET): TARGET (a test executable) uses the tests' precompiled header.
function(livod_reuse_test_pch target)
  if(LIVOD_PCH)
    target_compile_options(${target} PRIVATE -pthread)
    target_link_libraries(${target} PRIVATE Eigen3::Eigen)
    target_precompile_headers(${target} REUSE_FROM livod_test_pch)
  endif()
endfunction()

# livod_add_library(NAME SOURCES ... [PUBLIC_LIBS ...] [PRIVATE_LIBS ...])
# The include root is the repository root, so headers are included as "core/ring.hpp".
function(livod_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_LIBS;PRIVATE_LIBS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  if(LIVOD_UNITY_BUILD)
    # UNITY_BUILD_MODE BATCH, CMake's default batch size (8).
    set_target_properties(${name} PROPERTIES UNITY_BUILD ON)
    # In a batch GCC reports every class of one source that holds a type from another source's
    # anonymous namespace (-Wsubobject-linkage); the file-by-file builds still check each source.
    if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
      target_compile_options(${name} PRIVATE -Wno-subobject-linkage)
    endif()
  endif()
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR}/generated)
  target_link_libraries(${name} PUBLIC ${ARG_PUBLIC_LIBS} PRIVATE livod_warnings ${ARG_PRIVATE_LIBS})
endfunction()

# livod_add_test(NAME SOURCES ... LIBS ... [LABELS ...] [RUN_SERIAL] [COST seconds] [TIMEOUT seconds])
# Tests find the real captures through LIVOD_DATA_DIR (environment overrides the build default).
# RUN_SERIAL: ctest runs nothing else meanwhile (real-time tests that expect zero packet loss).
# COST: the expected run time of each of its tests, for ctest -j's order (costliest first).
# TIMEOUT: each of its tests' own limit, above the test preset's default (ctest's --timeout applies
# only to tests without one); 0 or absent: the default.
function(livod_add_test name)
  if(NOT LIVOD_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "RUN_SERIAL" "COST;TIMEOUT" "SOURCES;LIBS;LABELS" ${ARGN})
  set(serial FALSE)
  if(ARG_RUN_SERIAL)
    set(serial TRUE)
  endif()
  set(cost 0)
  if(ARG_COST)
    set(cost ${ARG_COST})
  endif()
  set(timeout "")
  if(ARG_TIMEOUT)
    set(timeout TIMEOUT ${ARG_TIMEOUT})
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} livod_test_support GTest::gtest GTest::gtest_main
                                        livod_warnings)
  livod_reuse_test_pch(${name})
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 120
    PROPERTIES LABELS "${ARG_LABELS}" ENVIRONMENT "LIVOD_DATA_DIR=${LIVOD_DATA_DIR}"
               ENVIRONMENT_MODIFICATION "LIVOD_SOURCE_DIR=set:${PROJECT_SOURCE_DIR}"
               RUN_SERIAL ${serial} COST ${cost} ${timeout})
endfunction()

# livod_glob_library(NAME DIR [PUBLIC_LIBS ...] [PRIVATE_LIBS ...])
# Every .cpp under DIR (recursively) except tests/ and fuzz/ subfolders belongs to the library, so
# adding a module file needs no CMake edit.
function(livod_glob_library name dir)
  cmake_parse_arguments(ARG "" "" "PUBLIC_LIBS;PRIVATE_LIBS" ${ARGN})
  file(GLOB_RECURSE srcs CONFIGURE_DEPENDS ${dir}/*.cpp)
  list(FILTER srcs EXCLUDE REGEX "/(tests|fuzz|bench)/")
  if(NOT srcs)
    add_library(${name} INTERFACE)
    target_include_directories(${name} INTERFACE ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR}/generated)
    target_link_libraries(${name} INTERFACE ${ARG_PUBLIC_LIBS})
    return()
  endif()
  livod_add_library(${name} SOURCES ${srcs} PUBLIC_LIBS ${ARG_PUBLIC_LIBS} PRIVATE_LIBS ${ARG_PRIVATE_LIBS})
endfunction()

# livod_glob_tests(PREFIX DIR LIBS ...): one test executable per DIR/*_test.cpp, named
# PREFIX_<file stem>. Tests whose stem ends in _threads_test also get the label "threads" (the
# TSan CI job runs those).
function(livod_glob_tests prefix dir)
  if(NOT LIVOD_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "LIBS" ${ARGN})
  file(GLOB tests CONFIGURE_DEPENDS ${dir}/*_test.cpp)
  foreach(t ${tests})
    get_filename_component(stem ${t} NAME_WE)
    # One label per test: gtest_discover_tests (CMake 3.25) splits a label list into separate
    # property arguments, so "unit;threads" would lose "threads".
    set(labels unit)
    if(stem MATCHES "_threads_test$")
      set(labels threads)
      set_property(GLOBAL APPEND PROPERTY LIVOD_THREADS_TESTS ${prefix}_${stem})
    endif()
    livod_add_test(${prefix}_${stem} SOURCES ${t} LIBS ${ARG_LIBS} LABELS ${labels})
  endforeach()
endfunction()

# livod_add_netns_test(NAME COMMAND cmd [args...] [LABELS ...] [TIMEOUT seconds] [ENVIRONMENT ...])
# A ctest test whose command runs in a fresh private network namespace (scripts/netns-run.sh):
# loopback only, multicast routed to lo, nothing can leave the machine, and tests running in
# parallel cannot hear each other. For LCM udpm, lcm-logger and UDP senders (e.g. end-to-end daemon
# tests). COMMAND may use generator expressions ($<TARGET_FILE:tgt>); child processes it starts are
# in the same namespace. Labels: "netns" plus LABELS. Without the privileges for a namespace the
# test fails with a message, unless LIVOD_NETNS_ALLOW_SKIP=1 (then it is reported as skipped).
function(livod_add_netns_test name)
  if(NOT LIVOD_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "RUN_SERIAL" "TIMEOUT" "COMMAND;LABELS;ENVIRONMENT" ${ARGN})
  if(NOT ARG_COMMAND)
    message(FATAL_ERROR "livod_add_netns_test(${name}): COMMAND is required")
  endif()
  add_test(NAME ${name} COMMAND bash ${PROJECT_SOURCE_DIR}/scripts/netns-run.sh ${ARG_COMMAND})
  set_tests_properties(${name} PROPERTIES
    SKIP_RETURN_CODE 77
    LABELS "netns;${ARG_LABELS}"
    ENVIRONMENT "LIVOD_DATA_DIR=${LIVOD_DATA_DIR};${ARG_ENVIRONMENT}"
    ENVIRONMENT_MODIFICATION "LIVOD_SOURCE_DIR=set:${PROJECT_SOURCE_DIR}")
  if(ARG_TIMEOUT)
    set_tests_properties(${name} PROPERTIES TIMEOUT ${ARG_TIMEOUT})
  endif()
  if(ARG_RUN_SERIAL)
    set_tests_properties(${name} PROPERTIES RUN_SERIAL TRUE)
  endif()
endfunction()

# livod_add_netns_gtest(NAME SOURCES ... LIBS ... [LABELS ...] [TIMEOUT seconds])
# A GoogleTest executable (like livod_add_test) registered as one ctest test that runs the whole
# binary in one fresh network namespace (livod_add_netns_test); its test cases share it.
function(livod_add_netns_gtest name)
  if(NOT LIVOD_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "RUN_SERIAL" "TIMEOUT" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} livod_test_support GTest::gtest GTest::gtest_main
                                        livod_warnings)
  livod_reuse_test_pch(${name})
  set(timeout_arg)
  if(ARG_TIMEOUT)
    set(timeout_arg TIMEOUT ${ARG_TIMEOUT})
  endif()
  set(serial_arg)
  if(ARG_RUN_SERIAL)
    set(serial_arg RUN_SERIAL)
  endif()
  livod_add_netns_test(${name} COMMAND $<TARGET_FILE:${name}> LABELS ${ARG_LABELS} ${timeout_arg}
                       ${serial_arg})
endfunction()
