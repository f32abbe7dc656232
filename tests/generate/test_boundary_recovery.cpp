// Boundary recovery's runaway rule: when the split rounds are called off.
#include <gtest/gtest.h>

#include <cstddef>
#include <vector>

#include "curvemesh/generate/boundary_recovery.hpp"

namespace {

using cm::generate::recovery_diverges;

// The first round after which recovery is called off, or -1: the rule is
// asked after every round, on the counts so far.
int first_divergent_round(const std::vector<std::size_t>& missing) {
  for (std::size_t n = 1; n <= missing.size(); ++n)
    if (recovery_diverges(std::span<const std::size_t>(missing.data(), n))) return static_cast<int>(n) - 1;
  return -1;
}

}  // namespace

// A KiCad connector (Altech AK300, 45 degrees): the missing edges and
// triangles after each round as recovery ran (it went on for 22 s to 30000
// Steiner points, then failed on an edge 7e-6 long).
TEST(RecoveryDivergence, ARunawayIsCalledOffWhenItHasGrownEightfoldOverFourRounds) {
  const std::vector<std::size_t> missing{
      563, 279, 244, 146, 61, 57,  113, 41,  79,  42,  32,  66,   45,   42,   48,   40,   33,  81,  61,
      51,  41,  41,  47,  36, 75,  21,  19,  63,  36,  23,  22,   14,   61,   25,   20,   28,   16,  34,
      9,   19,  7,   22,  20, 22,  33,  26,  36,  23,  18,  14,   37,   18,   18,   15,   22,   29,  39,
      45,  55,  60,  72,  105, 138, 193, 297, 409, 506, 647, 903, 1424, 2165, 3466, 5675, 10949 + 10100};
  EXPECT_EQ(first_divergent_round(missing), 72);  // 5675 > 8 * 563, after four rises (and many more)
}

TEST(RecoveryDivergence, ConvergingRecoveriesAreLeftToFinish) {
  // A temporary rise while splits reach a thin wall's scale.
  EXPECT_EQ(first_divergent_round({500, 800, 1200, 900, 300, 20, 0}), -1);
  // Four rises, but not yet eight times the start.
  EXPECT_EQ(first_divergent_round({100, 150, 220, 330, 500, 700}), -1);
  // Three rises only: a dip in between restarts the count.
  EXPECT_EQ(first_divergent_round({10, 100, 200, 150, 300, 600, 1200}), -1);
  EXPECT_EQ(first_divergent_round({10, 100, 200, 150, 300, 600, 1200, 2400}), 7);
  // Nothing missing at the start: the floor of one.
  EXPECT_EQ(first_divergent_round({0, 0, 0, 0, 0}), -1);
  EXPECT_EQ(first_divergent_round({0, 1, 2, 3, 9}), 4);
}
