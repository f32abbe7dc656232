#include "curvemesh/quality/measures.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "curvemesh/mesh/topology.hpp"

namespace cm::quality {

namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

double sum_squared_edges(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm() +
         (d - a).squaredNorm() + (d - b).squaredNorm() + (d - c).squaredNorm();
}

// Cube root of a positive normal double to a few ulps: the exponent divided
// by three in the bit pattern, then three Halley steps (cubic convergence
// from a start within a few percent). libm's cbrt is correctly rounded and
// three times slower, and the mean ratio, which needs one, is evaluated
// millions of times by the optimizer.
double cube_root(double x) {
  if (!(x >= std::numeric_limits<double>::min() && x <= std::numeric_limits<double>::max())) return std::cbrt(x);
  double y = std::bit_cast<double>(std::bit_cast<std::uint64_t>(x) / 3 + 0x2a9f7893782da1ceull);
  for (int k = 0; k < 3; ++k) {
    const double y3 = y * y * y;
    y *= (y3 + 2 * x) / (2 * y3 + x);
  }
  return y;
}

// Shared by the isotropic and metric forms: eta from a signed volume and the
// sum of squared edge lengths measured in the same metric.
double mean_ratio_from(double volume, double sum_sq) {
  if (!(sum_sq > 0) || volume == 0) return 0;
  const double eta = 12.0 * cube_root(9.0 * volume * volume) / sum_sq;
  return volume > 0 ? eta : -eta;
}

// The two faces through edge e of kTetEdges: those opposite its other two
// vertices.
constexpr std::array<std::array<int, 2>, 6> kOtherFaces = [] {
  std::array<std::array<int, 2>, 6> o{};
  for (int e = 0; e < 6; ++e) {
    int count = 0;
    for (int k = 0; k < 4; ++k)
      if (k != mesh::kTetEdges[e][0] && k != mesh::kTetEdges[e][1]) o[e][count++] = k;
  }
  return o;
}();

// Normals (right-hand rule over kFaceVerts) of the 4 faces, each of length
// twice the face area; outward for a positive tet.
std::array<Vec3, 4> face_normals(const std::array<const Vec3*, 4>& v) {
  std::array<Vec3, 4> n;
  for (int f = 0; f < 4; ++f) {
    const auto& fv = mesh::kFaceVerts[f];
    n[f] = (*v[fv[1]] - *v[fv[0]]).cross(*v[fv[2]] - *v[fv[0]]);
  }
  return n;
}

}  // namespace

double tet_signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).cross(c - a).dot(d - a) / 6.0;
}

std::array<double, 6> tet_edge_lengths(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const std::array<const Vec3*, 4> v{&a, &b, &c, &d};
  std::array<double, 6> out;
  for (int e = 0; e < 6; ++e)
    out[e] = (*v[mesh::kTetEdges[e][1]] - *v[mesh::kTetEdges[e][0]]).norm();
  return out;
}

double tet_mean_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return mean_ratio_from(tet_signed_volume(a, b, c, d), sum_squared_edges(a, b, c, d));
}

double tet_radius_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double volume = tet_signed_volume(a, b, c, d);
  if (!(volume > 0)) return std::numeric_limits<double>::infinity();
  const auto n = face_normals({&a, &b, &c, &d});
  const double area = 0.5 * (n[0].norm() + n[1].norm() + n[2].norm() + n[3].norm());
  const auto lengths = tet_edge_lengths(a, b, c, d);
  const double h_max = *std::max_element(lengths.begin(), lengths.end());
  // rho = 3V / area, so Q = alpha h_max area / (3V).
  const double alpha = std::sqrt(6.0) / 12.0;
  return alpha * h_max * area / (3.0 * volume);
}

double tet_inverse_radius_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double q = tet_radius_ratio(a, b, c, d);
  return std::isinf(q) ? 0.0 : 1.0 / q;
}

std::array<double, 6> tet_dihedral_angles(const Vec3& a, const Vec3& b, const Vec3& c,
                                          const Vec3& d) {
  const auto n = face_normals({&a, &b, &c, &d});
  std::array<double, 6> out;
  for (int e = 0; e < 6; ++e) {
    // The two faces sharing edge (i,j) are those opposite the other two vertices.
    const int i = mesh::kTetEdges[e][0];
    const int j = mesh::kTetEdges[e][1];
    int other[2];
    int count = 0;
    for (int k = 0; k < 4; ++k)
      if (k != i && k != j) other[count++] = k;
    const Vec3& nk = n[other[0]];
    const Vec3& nl = n[other[1]];
    if (nk.squaredNorm() == 0 || nl.squaredNorm() == 0) {
      out[e] = 0;
      continue;
    }
    // Both normals outward (or both inward for an inverted tet): the interior
    // angle is pi minus the angle between them. atan2 keeps precision near 0
    // and 180 degrees, where acos of a dot product does not.
    const double between = std::atan2(nk.cross(nl).norm(), nk.dot(nl));
    out[e] = 180.0 - between * kRadToDeg;
  }
  return out;
}

AngleRange tet_dihedral_range(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  // Only the two extreme angles need atan2 (the cost of this function in a
  // mesh summary): the others are ranked by a pseudo-angle, monotone in the
  // angle between the normals and as precise as atan2 near 0 and 180 degrees.
  const auto n = face_normals({&a, &b, &c, &d});
  double lo_key = INFINITY, hi_key = -INFINITY;
  int lo = -1, hi = -1;
  std::array<std::array<double, 2>, 6> sc{};  // |nk x nl|, nk . nl
  for (int e = 0; e < 6; ++e) {
    const int i = mesh::kTetEdges[e][0], j = mesh::kTetEdges[e][1];
    int other[2], count = 0;
    for (int k = 0; k < 4; ++k)
      if (k != i && k != j) other[count++] = k;
    const Vec3& nk = n[other[0]];
    const Vec3& nl = n[other[1]];
    double key;  // grows with the interior angle
    if (nk.squaredNorm() == 0 || nl.squaredNorm() == 0) {
      key = -1;  // a degenerate face: angle 0, as tet_dihedral_angles says
    } else {
      const double s = nk.cross(nl).norm(), cs = nk.dot(nl);
      sc[e] = {s, cs};
      // Pseudo-angle of the angle between the normals in [0, 2]; the
      // interior angle is 180 degrees minus it.
      const double between = cs >= 0 ? (s + cs > 0 ? s / (s + cs) : 0) : 1 + (-cs) / (s - cs);
      key = 2 - between;
    }
    if (key < lo_key) {
      lo_key = key;
      lo = e;
    }
    if (key > hi_key) {
      hi_key = key;
      hi = e;
    }
  }
  auto angle = [&](int e, double key) {
    if (key < 0) return 0.0;
    return 180.0 - std::atan2(sc[e][0], sc[e][1]) * kRadToDeg;
  };
  return {angle(lo, lo_key), angle(hi, hi_key)};
}

double tet_min_dihedral(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const auto n = face_normals({&a, &b, &c, &d});
  std::array<double, 4> inverse_norm;
  for (int f = 0; f < 4; ++f) {
    const double sq = n[f].squaredNorm();
    if (sq == 0) return 0;  // a degenerate face: angle 0, as tet_dihedral_angles says
    inverse_norm[f] = 1 / std::sqrt(sq);
  }
  // The interior angle at an edge is 180 degrees minus the angle between
  // the normals of the two faces through it: the smallest is where the unit
  // normals' dot product is least. Its value as tet_dihedral_range computes
  // it, with atan2's precision near 0 degrees.
  double least = INFINITY;
  int at = 0;
  for (int e = 0; e < 6; ++e) {
    const auto& o = kOtherFaces[e];
    const double cs = n[o[0]].dot(n[o[1]]) * (inverse_norm[o[0]] * inverse_norm[o[1]]);
    if (cs < least) {
      least = cs;
      at = e;
    }
  }
  const Vec3& nk = n[kOtherFaces[at][0]];
  const Vec3& nl = n[kOtherFaces[at][1]];
  return 180.0 - std::atan2(nk.cross(nl).norm(), nk.dot(nl)) * kRadToDeg;
}

bool tet_mean_ratio_at_least(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double r) {
  const double volume = tet_signed_volume(a, b, c, d), sum_sq = sum_squared_edges(a, b, c, d);
  if (!(volume > 0) || !(sum_sq > 0) || !std::isfinite(sum_sq)) return false;
  if (r <= 0) return true;
  // eta >= r  <=>  12^3 * 9 V^2 >= r^3 S^3. The margin (1e-9 relative,
  // against a few ulps of error on either side and in the cube root) keeps
  // the test one-sided.
  const double rs = r * sum_sq;
  return 15552.0 * volume * volume > rs * rs * rs * (1 + 1e-9);
}

bool tet_min_dihedral_at_least(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double degrees) {
  // The interior angle at an edge is acos(-cs), cs the cosine between the
  // outward normals of its faces, and acos(-cs) = 2 asin(sqrt((1 + cs) / 2))
  // >= sqrt(2 (1 + cs)). So every angle is at least T (radians) when every
  // cs >= T^2 / 2 - 1 = c0 (< 0 for T < 81 degrees), i.e. when
  // n_k.n_l >= 0 or (n_k.n_l)^2 <= c0^2 |n_k|^2 |n_l|^2. T is raised by a
  // margin for the round-off of this test and of tet_min_dihedral.
  const double t = (std::max(degrees, 0.0) * (1 + 1e-9) + 1e-9) / kRadToDeg;
  const double c0 = 0.5 * t * t - 1;
  if (!(c0 < 0)) return false;
  const double c0_sq = c0 * c0 * (1 - 1e-12);
  const auto n = face_normals({&a, &b, &c, &d});
  std::array<double, 4> sq;
  for (int f = 0; f < 4; ++f) {
    sq[f] = n[f].squaredNorm();
    if (!(sq[f] > 0) || !std::isfinite(sq[f])) return false;
  }
  for (const auto& o : kOtherFaces) {
    const double dot = n[o[0]].dot(n[o[1]]);
    if (dot < 0 && !(dot * dot <= c0_sq * sq[o[0]] * sq[o[1]])) return false;
  }
  return true;
}

double metric_length(const Vec3& e, const Mat3& metric) {
  return std::sqrt(std::max(0.0, e.dot(metric * e)));
}

double tet_metric_mean_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                             const Mat3& metric) {
  const std::array<const Vec3*, 4> v{&a, &b, &c, &d};
  double sum_sq = 0;
  for (const auto& e : mesh::kTetEdges) {
    const Vec3 edge = *v[e[1]] - *v[e[0]];
    sum_sq += edge.dot(metric * edge);
  }
  const double volume =
      std::sqrt(std::max(0.0, metric.determinant())) * tet_signed_volume(a, b, c, d);
  return mean_ratio_from(volume, sum_sq);
}

Mat3 metric_log_mean(std::span<const Mat3> metrics) {
  Mat3 log_sum = Mat3::Zero();
  for (const Mat3& m : metrics) {
    Eigen::SelfAdjointEigenSolver<Mat3> eig(m);
    const Vec3 log_values = eig.eigenvalues().array().max(std::numeric_limits<double>::min()).log();
    log_sum += eig.eigenvectors() * log_values.asDiagonal() * eig.eigenvectors().transpose();
  }
  log_sum /= static_cast<double>(metrics.size());
  Eigen::SelfAdjointEigenSolver<Mat3> eig(log_sum);
  const Vec3 values = eig.eigenvalues().array().exp();
  return eig.eigenvectors() * values.asDiagonal() * eig.eigenvectors().transpose();
}

double triangle_mean_ratio(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double sum_sq = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  if (!(sum_sq > 0)) return 0;
  const double area = 0.5 * (b - a).cross(c - a).norm();
  return 4.0 * std::sqrt(3.0) * area / sum_sq;
}

TetQuality evaluate_tet(const mesh::TetMesh& m, TetId t) {
  const auto& v = m.tet2verts[t];
  const Vec3& a = m.coords[v[0]];
  const Vec3& b = m.coords[v[1]];
  const Vec3& c = m.coords[v[2]];
  const Vec3& d = m.coords[v[3]];
  TetQuality q;
  q.volume = tet_signed_volume(a, b, c, d);
  q.mean_ratio = mean_ratio_from(q.volume, sum_squared_edges(a, b, c, d));
  q.radius_ratio = tet_radius_ratio(a, b, c, d);
  const AngleRange range = tet_dihedral_range(a, b, c, d);
  q.min_dihedral = range.min;
  q.max_dihedral = range.max;
  return q;
}

}  // namespace cm::quality
