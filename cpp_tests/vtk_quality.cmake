# VTK peer test of the hex stage (issue 6): reads the VTU / legacy VTK files that
# `cargo test --release --test hex_export` writes into target/hex-fixtures with VTK's
# own readers, checks node / element counts, and compares vtkMeshQuality's hex scaled
# Jacobian per element with the cell data "scaled_jacobian" the library wrote (1e-9).
# Included by the top-level CMakeLists.txt after GoogleTest is found and
# enable_testing() is called.
find_package(VTK 9.1 REQUIRED COMPONENTS CommonCore CommonDataModel IOLegacy IOXML FiltersVerdict)
if(NOT TARGET GTest::gtest_main)
  find_package(GTest 1.12 REQUIRED CONFIG)
  include(GoogleTest)
endif()
if(NOT CARGO)
  find_program(CARGO cargo HINTS $ENV{HOME}/.cargo/bin REQUIRED)
endif()
get_filename_component(SDDPM_HEX_ROOT "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
if(DEFINED ENV{CARGO_TARGET_DIR})
  set(SDDPM_HEX_FIXTURES_DIR "$ENV{CARGO_TARGET_DIR}/hex-fixtures")
else()
  set(SDDPM_HEX_FIXTURES_DIR "${SDDPM_HEX_ROOT}/target/hex-fixtures")
endif()

add_executable(test_vtk_quality ${CMAKE_CURRENT_LIST_DIR}/test_vtk_quality.cpp)
target_link_libraries(test_vtk_quality PRIVATE GTest::gtest GTest::gtest_main
  VTK::CommonCore VTK::CommonDataModel VTK::IOLegacy VTK::IOXML VTK::FiltersVerdict)
target_compile_definitions(test_vtk_quality PRIVATE SDDPM_HEX_FIXTURES="${SDDPM_HEX_FIXTURES_DIR}")
target_compile_options(test_vtk_quality PRIVATE -Wall -Wextra)
vtk_module_autoinit(TARGETS test_vtk_quality MODULES
  VTK::CommonCore VTK::CommonDataModel VTK::IOLegacy VTK::IOXML VTK::FiltersVerdict)

# the fixture files come from the Rust test
add_test(NAME hex_fixtures
  COMMAND ${CARGO} test --release --test hex_export
  WORKING_DIRECTORY ${SDDPM_HEX_ROOT})
set_tests_properties(hex_fixtures PROPERTIES FIXTURES_SETUP hex_fixtures TIMEOUT 1800)
gtest_discover_tests(test_vtk_quality DISCOVERY_TIMEOUT 60
  PROPERTIES FIXTURES_REQUIRED hex_fixtures TIMEOUT 600)
