#pragma once
// A load curve ([curves.<name>] of scenario.toml): a dimensionless factor of time that scales a
// boundary value, a load, gravity or a rigid piece's prescribed motion.
#include <string>
#include <vector>

namespace tactus::solver {

// [curves.<name>]: a dimensionless factor of time that scales a boundary value, a load or gravity.
struct CurveSpec {
  std::string name;
  std::vector<double> times, values;  // piecewise linear through (times[k], values[k]), constant beyond the ends
  bool smooth_step = false;           // instead: 0 before t0, 1 after t1, 3s^2 - 2s^3 between (s = (t - t0)/(t1 - t0))
  double t0 = 0, t1 = 0;
  double at(double t) const;
  // The integral from 0 to t (the displacement of a velocity scaled by this curve), exact.
  double integral(double t) const;
};

}  // namespace tactus::solver
