// The variational builder with the GL estimator (fast_gl_tests: needs a GL context), beside
// variational_builder_test.cpp, which uses the CPU twin.
#include <gtest/gtest.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <cstdlib>
#include <memory>
#include <string>

#include "builder/variational_builder.h"
#include "common/tree_io.h"
#include "data/analytic_meshes.h"
#include "fast/gl_estimator.h"
#include "fast/gl_test_util.h"
#include "test_common.h"

namespace vobb {
namespace {

// With GL too, the nodes of a level are searched at once (concurrent_estimates): the calls
// that wait at once are drawn in one round (gl_estimator.h), and each box keeps its own value,
// so the tree, and the counts of estimates, reuses and merges, are those of the search on one
// thread, for arenas of 1, 2, 3 and 8 threads. Where two threads run, some round must have held
// two nodes' calls: a GL draw takes milliseconds on llvmpipe against microseconds to plan a
// small batch, so over a depth-4 build's hundreds of calls the two threads' calls meet; a
// build whose calls never met would mean the nodes were not searched at once.
TEST(VariationalBuilderGl, NodesSearchedAtOnceGiveTheSameTree) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  VOBB_MAKE_GL(gl, mesh);
  const ObvEstimate estimate = [&](const std::vector<Obb>& boxes) {
    return gl->estimate(boxes, 8);
  };
  VariationalOptions o;
  o.depth = 4;
  VariationalReport serial;
  const std::string ref = tree_to_json(build_variational(mesh, o, estimate, nullptr, &serial));
  ASSERT_GT(serial.merges, 0u) << "no merge kept: the parallel sweep would go untested";
  o.concurrent_estimates = true;
  const size_t shared_before = gl->shared_round_trips();
  for (int threads : {1, 2, 3, 8}) {
    VariationalReport report;
    std::string got;
    tbb::task_arena(threads).execute(
        [&] { got = tree_to_json(build_variational(mesh, o, estimate, nullptr, &report)); });
    EXPECT_EQ(got, ref) << threads << " threads";
    EXPECT_EQ(report.estimates, serial.estimates) << threads;
    EXPECT_EQ(report.reused, serial.reused) << threads;
    EXPECT_EQ(report.merges, serial.merges) << threads;
    EXPECT_EQ(report.sweeps, serial.sweeps) << threads;
  }
  if (test::check_runs(tbb::info::default_concurrency() >= 2, "a second CPU")) {
    EXPECT_GT(gl->shared_round_trips(), shared_before) << "no two nodes' calls were drawn together";
  }
}

}  // namespace
}  // namespace vobb
