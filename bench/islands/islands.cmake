# Island-model benchmark: bench_islands (bench/islands/bench_islands.cpp), built on request
# (`make bench_islands`) like bench_peers, from whose problems and methods it borrows; SADE's
# column needs pagmo2 (scripts/setup --peers).
add_executable(bench_islands EXCLUDE_FROM_ALL
  bench/islands/bench_islands.cpp
  bench/peers/common.cpp
  bench/peers/instances.cpp
  bench/peers/problem.cpp
  bench/peers/methods.cpp)
target_link_libraries(bench_islands ${MME_LIBS})
if(Pagmo_FOUND)
  target_link_libraries(bench_islands Pagmo::pagmo)
  target_compile_definitions(bench_islands PRIVATE MME_HAVE_PAGMO=1)
endif()
if(Ceres_FOUND)
  target_link_libraries(bench_islands Ceres::ceres)
  target_compile_definitions(bench_islands PRIVATE MME_HAVE_CERES=1)
endif()
