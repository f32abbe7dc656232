#include "curvemesh/quality/bezier_jacobian.hpp"

#include <fmt/format.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>

#include "curvemesh/core/error.hpp"
#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/high_order.hpp"

namespace cm::quality {

namespace {

constexpr int kMaxNodes = simplex_count(kMaxBezierOrder);
constexpr int kMaxDerivs = simplex_count(kMaxBezierOrder - 1);
constexpr int kMaxCoefs = simplex_count(kMaxJacobianDegree);
constexpr int kMaxPairSums = simplex_count(2 * (kMaxBezierOrder - 1));
constexpr double kUnitRoundoff = std::numeric_limits<double>::epsilon() / 2;

// Pairs of local vertices along which a subdomain can be bisected (i < j).
constexpr std::array<std::array<int, 2>, 6> kPairs{
    {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};

double gamma(int n) { return n * kUnitRoundoff / (1 - n * kUnitRoundoff); }

// Everything that depends only on the geometric order p.
struct OrderTables {
  int order = 0;
  int num_nodes = 0;
  int num_derivs = 0;  // Bernstein basis of degree p-1
  int num_coefs = 0;   // Bernstein basis of degree 3(p-1)
  // Control point of rank m = sum_n L(m, n) * node n, L stored by rows
  // without its zeros (a control point of an edge depends on the nodes of
  // that edge alone, of a face on its closure): row m is the entries
  // [row_start[m], row_start[m + 1]) of lag2bez_sparse, by increasing node.
  double lag2bez_norm = 0;  // max row sum of |entries|
  struct Entry {
    int node;
    double weight;
  };
  std::vector<Entry> lag2bez_sparse;
  std::vector<int> row_start;
  // d/dxi_j control point of rank b = p (c[plus[j][b]] - c[base[b]]).
  std::array<std::vector<int>, 3> plus;
  std::vector<int> base;
  // det J = D1 . (D2 x D3) in two products of Bernstein expansions (see
  // compute_coefficients). First the cross products, of degree 2(p-1):
  // pair_sum[target] += weight * (D2[first] x D3[second]) over `pairs`;
  // then the dots: coefficient target += weight * D1[first] . pair_sum[second].
  struct ProductTerm {
    int first, second, target;
    double weight;
  };
  std::vector<ProductTerm> pairs;
  std::vector<ProductTerm> dots;
  std::array<int, 4> vertex_rank{};  // control point of each vertex (p e_k)
  int num_pair_sums = 0;  // Bernstein basis of degree 2(p-1)
  int pair_terms = 0;     // most cross products summed into one pair sum
  int dot_terms = 0;      // most dots summed into one coefficient
};

// Everything that depends only on the degree q of det J.
struct DegreeTables {
  int degree = 0;
  int num_coefs = 0;
  std::array<int, 4> corner{};
  // For each pair of kPairs, the lines of coefficients along that pair: runs
  // of ranks with a_i = r - s, a_j = s for s = 0..r, the other two fixed.
  std::array<std::vector<int>, 6> line_ranks;
  std::array<std::vector<int>, 6> line_lengths;
};

// The product of two Bernstein bases, B_a B_c = M(a) M(c) / M(a+c) B_{a+c}
// (M = multinomial), every pair of ranks (a, c) with the rank of a + c. For
// each a + c the weights sum to one (Vandermonde), so summing the products
// into the target is a convex combination; most_terms gets the largest
// number of pairs with one target.
std::vector<OrderTables::ProductTerm> product_expansion(const std::vector<MultiIndex>& first,
                                                        const std::vector<MultiIndex>& second, int& most_terms) {
  std::vector<OrderTables::ProductTerm> terms;
  std::vector<int> count;
  for (std::size_t a = 0; a < first.size(); ++a)
    for (std::size_t c = 0; c < second.size(); ++c) {
      MultiIndex sum;
      for (int k = 0; k < 4; ++k) sum[k] = first[a][k] + second[c][k];
      const int target = bernstein_rank(sum);
      terms.push_back({static_cast<int>(a), static_cast<int>(c), target,
                       multinomial(first[a]) * multinomial(second[c]) / multinomial(sum)});
      if (count.size() <= static_cast<std::size_t>(target)) count.resize(static_cast<std::size_t>(target) + 1, 0);
      ++count[static_cast<std::size_t>(target)];
    }
  most_terms = *std::max_element(count.begin(), count.end());
  return terms;
}

OrderTables build_order_tables(int p) {
  OrderTables t;
  t.order = p;
  t.num_nodes = simplex_count(p);
  t.num_derivs = simplex_count(p - 1);
  t.num_coefs = simplex_count(3 * (p - 1));
  const auto nodes = mesh::tet_node_indices(p);
  const auto controls = bernstein_indices(p);
  CM_ASSERT_OP(static_cast<int>(nodes.size()), ==, t.num_nodes);

  // Node n is the value of sum_m c_m B_m at bary = nodes[n] / p. Inverted in
  // long double so that the double entries are correctly rounded in practice.
  using MatL = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
  MatL eval(t.num_nodes, t.num_nodes);
  for (int n = 0; n < t.num_nodes; ++n)
    for (int m = 0; m < t.num_nodes; ++m) {
      long double v = multinomial(controls[static_cast<std::size_t>(m)]);
      for (int k = 0; k < 4; ++k)
        for (int e = 0; e < controls[static_cast<std::size_t>(m)][k]; ++e)
          v *= static_cast<long double>(nodes[static_cast<std::size_t>(n)][k]) / p;
      eval(n, m) = v;
    }
  const MatL inverse = eval.inverse();
  t.row_start.push_back(0);
  for (int m = 0; m < t.num_nodes; ++m) {
    double row = 0;
    for (int n = 0; n < t.num_nodes; ++n) {
      // Entries that are zero in exact arithmetic come out of the inversion
      // as rounding residue; the others are ratios of small integers.
      double v = static_cast<double>(inverse(m, n));
      if (std::abs(v) < 1e-12) v = 0;
      row += std::abs(v);
      if (v != 0 && n > 0) t.lag2bez_sparse.push_back({n, v});
    }
    t.row_start.push_back(static_cast<int>(t.lag2bez_sparse.size()));
    t.lag2bez_norm = std::max(t.lag2bez_norm, row);
  }

  for (int k = 0; k < 4; ++k) {
    MultiIndex corner{0, 0, 0, 0};
    corner[k] = p;
    t.vertex_rank[static_cast<std::size_t>(k)] = bernstein_rank(corner);
  }
  const auto derivs = bernstein_indices(p - 1);
  for (const MultiIndex& b : derivs) {
    MultiIndex at0 = b;
    ++at0[0];
    t.base.push_back(bernstein_rank(at0));
    for (int j = 0; j < 3; ++j) {
      MultiIndex at = b;
      ++at[j + 1];
      t.plus[static_cast<std::size_t>(j)].push_back(bernstein_rank(at));
    }
  }

  t.num_pair_sums = simplex_count(2 * (p - 1));
  t.pairs = product_expansion(derivs, derivs, t.pair_terms);
  t.dots = product_expansion(derivs, bernstein_indices(2 * (p - 1)), t.dot_terms);
  return t;
}

DegreeTables build_degree_tables(int q) {
  DegreeTables t;
  t.degree = q;
  t.num_coefs = simplex_count(q);
  for (int k = 0; k < 4; ++k) {
    MultiIndex a{0, 0, 0, 0};
    a[k] = q;
    t.corner[static_cast<std::size_t>(k)] = bernstein_rank(a);
  }
  for (std::size_t pr = 0; pr < kPairs.size(); ++pr) {
    const int i = kPairs[pr][0];
    const int j = kPairs[pr][1];
    int other[2];
    int count = 0;
    for (int k = 0; k < 4; ++k)
      if (k != i && k != j) other[count++] = k;
    for (int ak = 0; ak <= q; ++ak)
      for (int al = 0; ak + al <= q; ++al) {
        const int r = q - ak - al;
        for (int s = 0; s <= r; ++s) {
          MultiIndex a{};
          a[other[0]] = ak;
          a[other[1]] = al;
          a[i] = r - s;
          a[j] = s;
          t.line_ranks[pr].push_back(bernstein_rank(a));
        }
        t.line_lengths[pr].push_back(r + 1);
      }
  }
  return t;
}

const OrderTables& order_tables(int p) {
  static const auto tables = [] {
    std::array<OrderTables, kMaxBezierOrder + 1> t;
    for (int o = 1; o <= kMaxBezierOrder; ++o) t[o] = build_order_tables(o);
    return t;
  }();
  return tables[p];
}

const DegreeTables& degree_tables(int q) {
  static const auto tables = [] {
    std::array<DegreeTables, kMaxJacobianDegree + 1> t;
    for (int d = 0; d <= kMaxJacobianDegree; ++d) t[d] = build_degree_tables(d);
    return t;
  }();
  return tables[q];
}

void check_input(int order, std::span<const Vec3> nodes) {
  if (order < 1 || order > kMaxBezierOrder)
    throw std::invalid_argument(
        fmt::format("element order {} is not supported (1..{})", order, kMaxBezierOrder));
  if (static_cast<int>(nodes.size()) != simplex_count(order))
    throw std::invalid_argument(fmt::format("an order-{} tet has {} nodes, got {}", order,
                                            simplex_count(order), nodes.size()));
  for (const Vec3& x : nodes)
    if (!x.allFinite()) throw std::invalid_argument("tet node with a non-finite coordinate");
}

// Control points relative to node 0; returns max |coordinate| of the
// translated nodes (the scale of their rounding error).
double compute_control_points(const OrderTables& t, std::span<const Vec3> nodes, Vec3* control) {
  std::array<Vec3, kMaxNodes> rel;
  double scale = 0;
  for (int n = 0; n < t.num_nodes; ++n) {
    rel[static_cast<std::size_t>(n)] = nodes[static_cast<std::size_t>(n)] - nodes[0];
    scale = std::max(scale, rel[static_cast<std::size_t>(n)].cwiseAbs().maxCoeff());
  }
  // Node 0's column never counts: its translated position is zero.
  for (int m = 0; m < t.num_nodes; ++m) {
    Vec3 c = Vec3::Zero();
    for (int k = t.row_start[static_cast<std::size_t>(m)]; k < t.row_start[static_cast<std::size_t>(m) + 1]; ++k) {
      const auto& [n, w] = t.lag2bez_sparse[static_cast<std::size_t>(k)];
      c += w * rel[static_cast<std::size_t>(n)];
    }
    control[m] = c;
  }
  return scale;
}

// Coefficients of det J into coefs[0..num_coefs); returns the a-priori bound
// E0 on their rounding error (see the header comment and certify_jacobian).
double compute_coefficients(const OrderTables& t, std::span<const Vec3> nodes, double* coefs) {
  std::array<Vec3, kMaxNodes> control;
  const double node_scale = compute_control_points(t, nodes, control.data());
  std::array<std::array<Vec3, kMaxDerivs>, 3> deriv;
  double d_inf = 0;
  double d_norm2 = 0;
  for (int j = 0; j < 3; ++j)
    for (int b = 0; b < t.num_derivs; ++b) {
      const Vec3 d = t.order * (control[static_cast<std::size_t>(t.plus[j][b])] -
                                control[static_cast<std::size_t>(t.base[b])]);
      deriv[j][b] = d;
      d_inf = std::max(d_inf, d.cwiseAbs().maxCoeff());
      d_norm2 = std::max(d_norm2, d.squaredNorm());
    }
  // sqrt is monotone and correctly rounded: the largest norm, exactly.
  const double d_norm = std::sqrt(d_norm2);
  // det J = sum_b D1_b B_b . (sum_g sum_d D2_g x D3_d B_g B_d): the inner
  // product expanded first (nd^2 cross products into the degree-2(p-1)
  // basis), then the dots (nd times that basis): 450 products for P3 where
  // the triple products one by one would be 1000.
  std::array<Vec3, kMaxPairSums> pair_sum;
  std::fill(pair_sum.begin(), pair_sum.begin() + t.num_pair_sums, Vec3::Zero());
  for (const auto& [g, d, s, w] : t.pairs)
    pair_sum[static_cast<std::size_t>(s)] +=
        w * deriv[1][static_cast<std::size_t>(g)].cross(deriv[2][static_cast<std::size_t>(d)]);
  std::fill(coefs, coefs + t.num_coefs, 0.0);
  for (const auto& [b, s, target, w] : t.dots)
    coefs[target] += w * deriv[0][static_cast<std::size_t>(b)].dot(pair_sum[static_cast<std::size_t>(s)]);

  // Error budget, in the order the computation happens (|.| the 2-norm):
  // - control points: translation and the N-term products with lag2bez
  //   (whose entries are correctly rounded), |err| <= gamma(N+4) |L| max|y|;
  // - derivative control points: a difference times p, |err| <= e_d per
  //   coordinate; in exact arithmetic each D1 . (D2 x D3) then moves by at
  //   most (|d| + sqrt3 e_d)^3 - |d|^3 (Hadamard), and convex combinations
  //   of them by no more;
  // - with those inputs, d = the largest |D|: a cross product is within
  //   sqrt3 gamma(2) d^2, a pair sum (weights rounded twice, <= pair_terms
  //   terms) within sqrt3 gamma(pair_terms + 3) d^2 more: e_pair in all;
  // - a dot is within gamma(3) d (d^2 + e_pair) of the dot of what was
  //   computed, which is within d e_pair of the exact one, and the sum into
  //   a coefficient adds gamma(dot_terms + 3) of its terms' size.
  const double e_c = gamma(t.num_nodes + 4) * t.lag2bez_norm * node_scale;
  const double e_d = 2 * t.order * e_c + 2.02 * kUnitRoundoff * d_inf;
  const double pert = std::sqrt(3.0) * e_d;
  const double d_norm1 = d_norm + pert;
  const double input_err = pert * (d_norm1 * d_norm1 + d_norm1 * d_norm + d_norm * d_norm);
  const double d2 = d_norm1 * d_norm1;
  const double e_pair = 1.01 * std::sqrt(3.0) * (gamma(2) + gamma(t.pair_terms + 3)) * d2;
  const double dot_size = d_norm1 * (d2 + e_pair);
  const double rounding = d_norm1 * e_pair + (gamma(3) + 1.01 * gamma(t.dot_terms + 3)) * dot_size;
  return 1.1 * (input_err + rounding);
}

// One longest-edge bisection step of a subdomain: coefficients of the two
// halves by de Casteljau at t = 1/2 along every line parallel to pair pr.
// Child a keeps vertex i and puts the midpoint in slot j; child b keeps j and
// puts the midpoint in slot i.
void bisect_coefficients(const DegreeTables& t, std::size_t pr, const double* parent, double* a,
                         double* b) {
  const int* ranks = t.line_ranks[pr].data();
  std::array<double, kMaxJacobianDegree + 1> w;
  for (int len : t.line_lengths[pr]) {
    const int r = len - 1;
    for (int s = 0; s <= r; ++s) w[static_cast<std::size_t>(s)] = parent[ranks[s]];
    a[ranks[0]] = w[0];
    b[ranks[r]] = w[static_cast<std::size_t>(r)];
    for (int level = 1; level <= r; ++level) {
      for (int s = 0; s + level <= r; ++s)
        w[static_cast<std::size_t>(s)] =
            0.5 * (w[static_cast<std::size_t>(s)] + w[static_cast<std::size_t>(s + 1)]);
      a[ranks[level]] = w[0];
      b[ranks[r - level]] = w[static_cast<std::size_t>(r - level)];
    }
    ranks += len;
  }
}

std::size_t longest_pair(const std::array<Bary, 4>& verts) {
  // Lengths in xi = (l1, l2, l3); ties go to the first pair, deterministically.
  std::size_t best = 0;
  double best_len = -1;
  for (std::size_t pr = 0; pr < kPairs.size(); ++pr) {
    const Bary& u = verts[static_cast<std::size_t>(kPairs[pr][0])];
    const Bary& v = verts[static_cast<std::size_t>(kPairs[pr][1])];
    double len = 0;
    for (int k = 1; k < 4; ++k) len += (u[k] - v[k]) * (u[k] - v[k]);
    if (len > best_len) {
      best_len = len;
      best = pr;
    }
  }
  return best;
}

struct Domain {
  double min_coef;
  double max_coef;
  int slot;
  int depth;
};

// Best-first subdivision state of one certification.
class Search {
 public:
  Search(const DegreeTables& t, double err, const ValidityOptions& opt, ValidityReport& rep)
      : tables_(t), err_(err), opt_(opt), rep_(rep) {}

  void note_value(double v, const Bary& at) {
    if (v < rep_.min_upper) {
      rep_.min_upper = v;
      rep_.where = at;
    }
    rep_.max_lower = std::max(rep_.max_lower, v);
    if (v <= err_) invalid_ = true;
  }

  void push(const double* coefs, const std::array<Bary, 4>& verts, int depth) {
    int slot;
    if (!free_.empty()) {
      slot = free_.back();
      free_.pop_back();
    } else {
      slot = static_cast<int>(verts_.size());
      verts_.emplace_back();
      pool_.resize(pool_.size() + static_cast<std::size_t>(tables_.num_coefs));
    }
    std::copy(coefs, coefs + tables_.num_coefs, coefs_of(slot));
    verts_[static_cast<std::size_t>(slot)] = verts;
    const auto [lo, hi] = std::minmax_element(coefs, coefs + tables_.num_coefs);
    heap_.push_back({*lo, *hi, slot, depth});
    std::push_heap(heap_.begin(), heap_.end(), by_min);
    rep_.depth_reached = std::max(rep_.depth_reached, depth);
  }

  void run(double gap_scale) {
    int locate_left = opt_.locate_splits;
    std::vector<double> child_a(static_cast<std::size_t>(tables_.num_coefs));
    std::vector<double> child_b(static_cast<std::size_t>(tables_.num_coefs));
    while (!heap_.empty()) {
      const Domain top = heap_.front();
      if (invalid_) {
        // Only a subdomain whose bound is below the least known value (by more
        // than the rounding) can hold a point worse than `where`.
        if (locate_left <= 0 || top.min_coef >= rep_.min_upper - err_) break;
      } else if (top.min_coef > err_) {
        if (opt_.bound_tolerance <= 0 ||
            rep_.min_upper - top.min_coef <= opt_.bound_tolerance * gap_scale)
          break;
      }
      if (rep_.splits >= opt_.max_splits) break;
      std::pop_heap(heap_.begin(), heap_.end(), by_min);
      heap_.pop_back();
      if (top.depth >= opt_.max_depth) {
        retired_min_ = std::min(retired_min_, top.min_coef);
        retired_max_ = std::max(retired_max_, top.max_coef);
        free_.push_back(top.slot);
        continue;
      }
      split(top, child_a.data(), child_b.data());
      if (invalid_) --locate_left;
    }
  }

  bool invalid() const { return invalid_; }

  // Least and largest coefficient over the final subdivision.
  std::pair<double, double> bounds() const {
    double lo = retired_min_;
    double hi = retired_max_;
    for (const Domain& d : heap_) {
      lo = std::min(lo, d.min_coef);
      hi = std::max(hi, d.max_coef);
    }
    return {lo, hi};
  }

 private:
  static bool by_min(const Domain& x, const Domain& y) { return x.min_coef > y.min_coef; }

  double* coefs_of(int slot) {
    return pool_.data() +
           static_cast<std::size_t>(slot) * static_cast<std::size_t>(tables_.num_coefs);
  }

  void split(const Domain& d, double* a, double* b) {
    ++rep_.splits;
    const std::array<Bary, 4> verts = verts_[static_cast<std::size_t>(d.slot)];
    const std::size_t pr = longest_pair(verts);
    const auto i = static_cast<std::size_t>(kPairs[pr][0]);
    const auto j = static_cast<std::size_t>(kPairs[pr][1]);
    bisect_coefficients(tables_, pr, coefs_of(d.slot), a, b);
    free_.push_back(d.slot);
    Bary mid;
    for (int k = 0; k < 4; ++k) mid[k] = 0.5 * (verts[i][k] + verts[j][k]);
    note_value(a[tables_.corner[j]], mid);
    std::array<Bary, 4> verts_a = verts;
    std::array<Bary, 4> verts_b = verts;
    verts_a[j] = mid;
    verts_b[i] = mid;
    push(a, verts_a, d.depth + 1);
    push(b, verts_b, d.depth + 1);
  }

  const DegreeTables& tables_;
  double err_;
  const ValidityOptions& opt_;
  ValidityReport& rep_;
  bool invalid_ = false;
  std::vector<double> pool_;
  std::vector<std::array<Bary, 4>> verts_;
  std::vector<int> free_;
  std::vector<Domain> heap_;
  double retired_min_ = std::numeric_limits<double>::infinity();
  double retired_max_ = -std::numeric_limits<double>::infinity();
};

double scaled_lower(const ValidityReport& r) {
  if (r.min_lower > 0) return r.min_lower / r.max_upper;
  if (r.max_lower > 0) return r.min_lower / r.max_lower;
  return -std::numeric_limits<double>::infinity();
}

ValidityReport certify_linear(std::span<const Vec3> nodes) {
  ValidityReport rep;
  const double det = (nodes[1] - nodes[0]).cross(nodes[2] - nodes[0]).dot(nodes[3] - nodes[0]);
  const int sign =
      predicates::orient3d(nodes[0].data(), nodes[1].data(), nodes[2].data(), nodes[3].data());
  // The reported value follows the exact sign, even when rounding flipped det.
  double value = det;
  if (sign == 0)
    value = 0;
  else if ((det > 0) != (sign > 0))
    value = sign * std::numeric_limits<double>::min();
  rep.verdict = sign > 0 ? Validity::kValid : Validity::kInvalid;
  rep.min_lower = rep.min_upper = rep.max_upper = rep.max_lower = value;
  rep.scaled_jacobian_lower = scaled_lower(rep);
  rep.where = {1, 0, 0, 0};
  rep.where_entity = {0, 0};
  return rep;
}

}  // namespace

SubEntity classify_bary(const Bary& bary, double tol) {
  std::array<int, 4> on{};
  int count = 0;
  for (int k = 0; k < 4; ++k)
    if (bary[k] > tol) on[count++] = k;
  if (count == 0) {
    const auto largest = std::max_element(bary.begin(), bary.end()) - bary.begin();
    return {0, static_cast<int>(largest)};
  }
  if (count == 1) return {0, on[0]};
  if (count == 2) {
    for (int e = 0; e < 6; ++e) {
      const auto& ev = mesh::kTetEdges[e];
      if ((ev[0] == on[0] && ev[1] == on[1]) || (ev[0] == on[1] && ev[1] == on[0])) return {1, e};
    }
  }
  if (count == 3) {
    // The face opposite the one vertex that is off.
    for (int k = 0; k < 4; ++k)
      if (!(bary[k] > tol)) return {2, k};
  }
  return {3, 0};
}

std::vector<double> jacobian_bezier_coefficients(int order, std::span<const Vec3> nodes) {
  check_input(order, nodes);
  const OrderTables& t = order_tables(order);
  std::vector<double> coefs(static_cast<std::size_t>(t.num_coefs));
  compute_coefficients(t, nodes, coefs.data());
  return coefs;
}

std::vector<Vec3> geometry_control_points(int order, std::span<const Vec3> nodes) {
  check_input(order, nodes);
  const OrderTables& t = order_tables(order);
  std::vector<Vec3> control(static_cast<std::size_t>(t.num_nodes));
  compute_control_points(t, nodes, control.data());
  for (Vec3& c : control) c += nodes[0];
  return control;
}

ValidityReport certify_jacobian(int order, std::span<const Vec3> nodes,
                                const ValidityOptions& options, std::span<double> coefficients) {
  check_input(order, nodes);
  if (!coefficients.empty() && static_cast<int>(coefficients.size()) != simplex_count(3 * (order - 1)))
    throw std::invalid_argument(fmt::format("det J of an order-{} tet has {} Bernstein coefficients, not {}", order,
                                            simplex_count(3 * (order - 1)), coefficients.size()));
  if (order == 1) {
    if (!coefficients.empty()) coefficients[0] = (nodes[1] - nodes[0]).cross(nodes[2] - nodes[0]).dot(nodes[3] - nodes[0]);
    return certify_linear(nodes);
  }

  const OrderTables& ot = order_tables(order);
  const DegreeTables& dt = degree_tables(3 * (order - 1));
  std::array<double, kMaxCoefs> root;
  const double err0 = compute_coefficients(ot, nodes, root.data());
  std::copy(root.begin(), root.begin() + static_cast<std::ptrdiff_t>(coefficients.size()), coefficients.begin());
  const auto [lo_it, hi_it] = std::minmax_element(root.begin(), root.begin() + dt.num_coefs);
  const double lo = *lo_it;
  const double hi = *hi_it;
  // Subdivision only averages coefficients: each bisection adds at most
  // `degree` roundings of size u max|coef| along any line.
  const double magnitude = std::max(std::abs(lo), std::abs(hi)) + err0;
  const double err = err0 + 1.1 * (options.max_depth * dt.degree + 2) * kUnitRoundoff * magnitude;

  ValidityReport rep;
  rep.rounding_bound = err;
  rep.min_upper = std::numeric_limits<double>::infinity();
  rep.max_lower = -std::numeric_limits<double>::infinity();
  // With refine_below, first decide validity only; the tolerance then
  // continues the same best-first subdivision, which is the sequence of
  // splits a run with the tolerance from the start makes.
  const bool two_phase = options.refine_below > 0 && options.bound_tolerance > 0;
  ValidityOptions phase = options;
  if (two_phase) phase.bound_tolerance = 0;
  Search search(dt, err, phase, rep);
  const std::array<Bary, 4> unit{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
  for (std::size_t k = 0; k < 4; ++k)
    search.note_value(root[static_cast<std::size_t>(dt.corner[k])], unit[k]);

  const double gap_scale = magnitude;
  const auto settled = [&](double tolerance) {
    return lo > err && (tolerance <= 0 || rep.min_upper - lo <= tolerance * gap_scale);
  };
  // The common case for a good element: no subdivision, no allocation.
  double lower = lo, upper = hi;
  bool searched = false;
  const auto search_on = [&] {
    if (!searched) search.push(root.data(), unit, 0);
    searched = true;
    search.run(gap_scale);
    std::tie(lower, upper) = search.bounds();
  };
  if (!settled(phase.bound_tolerance)) search_on();
  if (two_phase && !search.invalid() && lower > err && lower / upper < options.refine_below) {
    phase.bound_tolerance = options.bound_tolerance;
    if (searched || !settled(phase.bound_tolerance)) search_on();
  }
  rep.min_lower = lower;
  rep.max_upper = upper;
  if (search.invalid())
    rep.verdict = Validity::kInvalid;
  else
    rep.verdict = lower > err ? Validity::kValid : Validity::kUndetermined;
  rep.where_entity = classify_bary(rep.where, 0);
  rep.scaled_jacobian_lower = scaled_lower(rep);
  return rep;
}

NearStraightBounds near_straight_bounds(int order, std::span<const Vec3> nodes) {
  check_input(order, nodes);
  NearStraightBounds out;
  if (order < 2) return out;
  const OrderTables& t = order_tables(order);
  std::array<Vec3, kMaxNodes> control;
  const double node_scale = compute_control_points(t, nodes, control.data());
  const auto vertex = [&](int k) { return control[static_cast<std::size_t>(t.vertex_rank[static_cast<std::size_t>(k)])]; };
  Mat3 j0;
  for (int j = 0; j < 3; ++j) j0.col(j) = vertex(j + 1) - vertex(0);
  const double det = j0.determinant();
  const double size = j0.squaredNorm();
  // A straight tet this flat has a determinant whose relative rounding is
  // no longer negligible: the full certification decides.
  if (!(det > 1e-6 * size * std::sqrt(size))) return out;
  const Mat3 inverse = j0.inverse();
  // J(xi) = J0 (I + A(xi)) with A = sum_b A_b B_b(xi), A_b = J0^-1 (D_b - J0)
  // for the derivative control points D_b (columns D_{j,b}). det(I + A) =
  // 1 + tr A + c2(A) + det A: tr A lies within the A_b's traces (Bernstein
  // weights are a convex combination), |A|_F under the largest |A_b|_F = s,
  // and |c2(A)| <= |A|_F^2, |det A| <= |A|_F^3 / sqrt(27).
  double t_lo = INFINITY, t_hi = -INFINITY, t_sum = 0, s2 = 0;
  for (int b = 0; b < t.num_derivs; ++b) {
    Mat3 d;
    for (int j = 0; j < 3; ++j)
      d.col(j) = order * (control[static_cast<std::size_t>(t.plus[j][b])] - control[static_cast<std::size_t>(t.base[b])]);
    const Mat3 a = inverse * (d - j0);
    t_lo = std::min(t_lo, a.trace());
    t_hi = std::max(t_hi, a.trace());
    t_sum += a.trace();
    s2 = std::max(s2, a.squaredNorm());
  }
  const double t_mean = t_sum / t.num_derivs;
  // Rounding: the derivative control points are within e_d per coordinate
  // (as in compute_coefficients), J0's columns within a few units of the
  // translated nodes; through J0^-1 that moves every A_b by at most
  // `slack` (Frobenius), its trace by sqrt(3) times that. The products
  // here add relative errors far below the 1e-8 kept.
  const double e_c = gamma(t.num_nodes + 4) * t.lag2bez_norm * node_scale;
  const double per_coordinate = 2 * order * e_c + 8 * kUnitRoundoff * node_scale;
  const double slack = inverse.norm() * 3 * per_coordinate * 1.01 + 1e-8 * std::sqrt(s2);
  const double s = std::sqrt(s2) * (1 + 1e-8) + slack;
  const double higher = s * s + s * s * s / std::sqrt(27.0);
  const double pad = std::sqrt(3.0) * slack;
  const double lo = 1 + t_lo - pad - std::abs(t_lo) * 1e-8 - higher;
  const double hi = 1 + t_hi + pad + std::abs(t_hi) * 1e-8 + higher;
  const double mean = 1 + t_mean + pad + std::abs(t_mean) * 1e-8 + higher;
  if (!(lo > 0)) return out;
  out.ratio = lo / hi * (1 - 1e-12);
  out.mean_ratio = lo / mean * (1 - 1e-12);
  return out;
}

ValidityReport certify_tet(const mesh::TetMesh& m, TetId t, const ValidityOptions& options) {
  const auto nodes = mesh::gather_tet_nodes(m, t);
  return certify_jacobian(m.high_order.order(), nodes, options);
}

}  // namespace cm::quality
