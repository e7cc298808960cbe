# Peer-optimiser benchmark: bench_peers, run by scripts/bench.
# pagmo2 (CMA-ES, SADE) and Ceres (Levenberg-Marquardt) are benchmark-only dependencies
# (`scripts/setup --peers` installs libpagmo-dev libceres-dev): the package builds and runs
# without them. The target is excluded from the default build (`make`/`catkin_make` never build
# it); `scripts/bench` builds it explicitly. With both peers found it compares all seven methods;
# with a peer missing it is built without that peer's methods (and says so when it runs), so
# `scripts/bench --quick` still exercises the rest.
find_package(Pagmo QUIET)
find_package(Ceres QUIET)

add_executable(bench_peers EXCLUDE_FROM_ALL
  bench/peers/bench_peers.cpp
  bench/peers/common.cpp
  bench/peers/instances.cpp
  bench/peers/speed_part.cpp
  bench/peers/map_part.cpp
  bench/peers/scaling_part.cpp
  bench/peers/summary.cpp
  bench/peers/summary_targets.cpp
  bench/peers/summary_tables.cpp
  bench/peers/summary_map.cpp
  bench/peers/summary_failures.cpp
  bench/peers/problem.cpp
  bench/peers/methods.cpp)
target_link_libraries(bench_peers ${MME_LIBS})

set(_mme_missing_peers "")
if(Pagmo_FOUND)
  target_link_libraries(bench_peers Pagmo::pagmo)
  target_compile_definitions(bench_peers PRIVATE MME_HAVE_PAGMO=1)
else()
  list(APPEND _mme_missing_peers "pagmo2 (libpagmo-dev)")
endif()
if(Ceres_FOUND)
  target_link_libraries(bench_peers Ceres::ceres)
  target_compile_definitions(bench_peers PRIVATE MME_HAVE_CERES=1)
else()
  list(APPEND _mme_missing_peers "Ceres (libceres-dev)")
endif()
if(_mme_missing_peers)
  string(REPLACE ";" ", " _mme_missing_peers "${_mme_missing_peers}")
  message(STATUS "bench_peers: ${_mme_missing_peers} not found: the peer benchmark is built without "
                 "those methods (scripts/setup --peers installs them)")
else()
  message(STATUS "bench_peers: pagmo2 and Ceres found: the peer benchmark compares every method")
endif()
unset(_mme_missing_peers)
