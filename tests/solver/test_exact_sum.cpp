// ExactSum (the stress pass's sums over atoms): the exact sum rounded once, whatever the order or
// the grouping. References: sums whose exact value is known by construction, and a 113-bit
// (__float128) sum that is itself exact for the values drawn.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "tactus/solver/exact_sum.hpp"

using tactus::solver::ExactSum;

namespace {
double exact_sum(const std::vector<double>& values) {
  ExactSum s;
  for (double x : values) s.add(x);
  return s.value();
}
}  // namespace

TEST(ExactSum, CancellationThatPlainSummationLoses) {
  // 1e100 + 1 - 1e100 is 1; added left to right in doubles it is 0.
  const std::vector<double> values{1e100, 1.0, -1e100};
  double plain = 0;
  for (double x : values) plain += x;
  std::printf("exact %.17g, plain %.17g (reference 1)\n", exact_sum(values), plain);
  EXPECT_EQ(exact_sum(values), 1.0);
  EXPECT_EQ(plain, 0.0);
  // The extremes of the range: the largest double twice and back, and subnormals.
  const double big = std::numeric_limits<double>::max(), tiny = std::numeric_limits<double>::denorm_min();
  EXPECT_EQ(exact_sum({big, big, -big}), big);
  EXPECT_EQ(exact_sum({big, big}), std::numeric_limits<double>::infinity());
  EXPECT_EQ(exact_sum({tiny, tiny, tiny}), 3 * tiny);
  EXPECT_EQ(exact_sum({1.0, tiny, -1.0}), tiny);
  EXPECT_EQ(exact_sum({-2.5, -0.25}), -2.75);
  EXPECT_EQ(exact_sum({}), 0.0);
  EXPECT_EQ(exact_sum({0.1, -0.1}), 0.0);
}

TEST(ExactSum, RoundsOnceToNearestEven) {
  // 1 + 2^-53 is a tie between 1 and 1 + 2^-52: to even, 1; a further 2^-200 breaks the tie upwards.
  const double half_ulp = std::ldexp(1.0, -53);
  EXPECT_EQ(exact_sum({1.0, half_ulp}), 1.0);
  EXPECT_EQ(exact_sum({1.0, half_ulp, std::ldexp(1.0, -200)}), 1.0 + 2 * half_ulp);
  EXPECT_EQ(exact_sum({1.0 + 2 * half_ulp, half_ulp}), 1.0 + 4 * half_ulp);  // the odd one up to even
}

TEST(ExactSum, NonFiniteValues) {
  EXPECT_TRUE(std::isnan(exact_sum({1.0, std::nan("")})));
  EXPECT_EQ(exact_sum({1.0, std::numeric_limits<double>::infinity()}), std::numeric_limits<double>::infinity());
  EXPECT_EQ(exact_sum({-std::numeric_limits<double>::infinity(), 3.0}), -std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(exact_sum({std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()})));
}

TEST(ExactSum, SameBitsInAnyOrderAndGroupingAsTheExactSum) {
  // 20,000 values of both signs, magnitudes 2^-20 .. 2^21: their lowest bit is at least 2^-72 and
  // any partial sum below 2^36, so every partial sum fits 108 < 113 bits: the __float128 sum is
  // exact, and its conversion rounds it once.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> mantissa(1.0, 2.0);
  std::uniform_int_distribution<int> exponent(-20, 20);
  std::vector<double> values(20000);
  for (double& x : values) x = std::ldexp(mantissa(rng), exponent(rng)) * (rng() % 2 ? 1 : -1);
  __extension__ __float128 reference = 0;
  for (double x : values) reference += x;
  const double expected = static_cast<double>(reference);
  double plain = 0;
  for (double x : values) plain += x;
  const double forward = exact_sum(values);
  std::reverse(values.begin(), values.end());
  const double backward = exact_sum(values);
  std::shuffle(values.begin(), values.end(), rng);
  // In 7 groups (as 7 ranks would), each group's words added to the whole.
  ExactSum whole;
  for (std::size_t g = 0; g < 7; ++g) {
    ExactSum part;
    for (std::size_t i = values.size() * g / 7; i < values.size() * (g + 1) / 7; ++i) part.add(values[i]);
    whole.add_words(part.words().data());
  }
  std::printf("reference %.17g: forward %.17g, backward %.17g, 7 groups shuffled %.17g; plain left-to-right %.17g\n", expected, forward, backward,
              whole.value(), plain);
  EXPECT_EQ(forward, expected);
  EXPECT_EQ(backward, expected);
  EXPECT_EQ(whole.value(), expected);
}
