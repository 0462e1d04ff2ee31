#include "hivecal/core/types.hpp"

namespace hivecal {

Mat3 rotation_x(double angle_rad) {
  double s = 0.0;
  double c = 0.0;
  math::sincos(angle_rad, &s, &c);
  Mat3 r;
  r << 1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c;
  return r;
}

Mat3 rotation_y(double angle_rad) {
  double s = 0.0;
  double c = 0.0;
  math::sincos(angle_rad, &s, &c);
  Mat3 r;
  r << c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c;
  return r;
}

Mat3 rotation_z(double angle_rad) {
  double s = 0.0;
  double c = 0.0;
  math::sincos(angle_rad, &s, &c);
  Mat3 r;
  r << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
  return r;
}

}  // namespace hivecal
