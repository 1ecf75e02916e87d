#include "haptic/motion.hpp"

namespace haptic {
namespace {

Vec3 combine(double ca, const Vec3& a, double cb, const Vec3& b, double cc, const Vec3& c, double cd,
             const Vec3& d) {
  return {ca * a.x + cb * b.x + cc * c.x + cd * d.x, ca * a.y + cb * b.y + cc * c.y + cd * d.y,
          ca * a.z + cb * b.z + cc * c.z + cd * d.z};
}

}  // namespace

Vec3 interpolate_position(const State& a, const State& b, double t) {
  const double h = b.server_time - a.server_time;
  if (!(h > 0.0)) return a.position;
  const double s = (t - a.server_time) / h;  // 0 at a, 1 at b
  const double s2 = s * s, s3 = s2 * s;
  // The Hermite basis: h00 p_a + h10 h v_a + h01 p_b + h11 h v_b.
  const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2,
               h11 = s3 - s2;
  return combine(h00, a.position, h10 * h, a.velocity, h01, b.position, h11 * h, b.velocity);
}

Vec3 predict_position(const State& previous, const State& latest, double t) {
  const double delta = t - latest.server_time;
  const double h = latest.server_time - previous.server_time;
  const double k = h > 0.0 ? 0.5 * delta * delta / h : 0.0;  // ½ Δ² / h, times the velocity change
  return combine(1.0, latest.position, delta + k, latest.velocity, -k, previous.velocity, 0.0, Vec3{});
}

}  // namespace haptic
