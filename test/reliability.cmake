# Reliability helpers (docs/reliability.md), built with the package:
#  check_model_file: does a model file load (crash-restart test, no python/yaml needed)
#  soak_publisher:   drives scripts/soak (a long faulty 120 Hz MarkerFrame stream)
add_executable(check_model_file test/reliability/check_model_file.cpp)
target_link_libraries(check_model_file ${MME_LIBS})

add_executable(soak_publisher test/soak/soak_publisher.cpp)
target_link_libraries(soak_publisher mme_ros ${MME_LIBS} ${catkin_LIBRARIES})
add_dependencies(soak_publisher ${PROJECT_NAME}_generate_messages_cpp)

if(CATKIN_ENABLE_TESTING)
  catkin_add_gtest(test_online_estimator_input test/reliability/test_online_estimator_input.cpp)
  target_link_libraries(test_online_estimator_input ${MME_LIBS} gtest_main)
endif()

# structure_sweep: structure selection on windows of the real captures (scripts/sweep-structure,
# test/cli/test_structure_sweep.sh, and scripts/test --sanitize under the sanitizers).
add_executable(structure_sweep test/reliability/structure_sweep.cpp src/tools/cli_args.cpp)
target_link_libraries(structure_sweep ${MME_LIBS})
