// Closed-form moments of the pieces of a rounded sphero-polyhedron (see MassProperties.hpp).
#include "sdem/MassProperties.hpp"

#include <cmath>
#include <vector>

#include "sdem/SpheroPolyhedron.hpp"

namespace mpmsdem {
namespace sdem {
namespace {

constexpr Real kPi = 3.14159265358979323846;

// Moments of the prism {p + t d : p in polygon, 0 <= t <= h}; the polygon is planar and
// convex (vertex list in order), d a unit vector perpendicular to its plane.
Moments prism(const std::vector<Vec3>& poly, const Vec3& d, Real h) {
  Real area = 0;
  Vec3 s1 = Vec3::Zero();  // integral of p over the polygon
  Mat3 s2 = Mat3::Zero();  // integral of p p^T over the polygon
  for (size_t i = 1; i + 1 < poly.size(); ++i) {
    const Vec3& a = poly[0];
    const Vec3& b = poly[i];
    const Vec3& c = poly[i + 1];
    const Real at = 0.5 * (b - a).cross(c - a).norm();
    const Vec3 sum = a + b + c;
    area += at;
    s1 += at * sum / 3.0;
    s2 += at / 12.0 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + sum * sum.transpose());
  }
  Moments m;
  m.m0 = area * h;
  m.m1 = h * s1 + 0.5 * h * h * area * d;
  m.m2 = h * s2 + 0.5 * h * h * (s1 * d.transpose() + d * s1.transpose()) + h * h * h / 3.0 * area * d * d.transpose();
  return m;
}

// Moments of the core polyhedron: signed tetrahedra (origin, fan triangle of each face).
Moments corePolyhedron(const SpheroPolyhedron& s) {
  Moments m;
  for (const CoreFace& f : s.faces) {
    const Vec3& a = s.vertices[f.loop[0]];
    for (size_t i = 1; i + 1 < f.loop.size(); ++i) {
      const Vec3& b = s.vertices[f.loop[i]];
      const Vec3& c = s.vertices[f.loop[i + 1]];
      const Real v = a.dot(b.cross(c)) / 6.0;
      const Vec3 sum = a + b + c;
      m.m0 += v;
      m.m1 += v * sum / 4.0;
      m.m2 += v / 20.0 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + sum * sum.transpose());
    }
  }
  return m;
}

// Cylindrical sector x = a + s u + r (cos(phi) e1 + sin(phi) e2), s in [0, L], r in [0, R],
// phi in [0, theta]; e1, e2, u orthonormal.
Moments wedge(const Vec3& a, const Vec3& u, Real L, const Vec3& e1, const Vec3& e2, Real theta, Real R) {
  const Real area = 0.5 * theta * R * R;  // cross-section area
  const Vec3 dirInt = std::sin(theta) * e1 + (1.0 - std::cos(theta)) * e2;  // integral of the direction over phi
  const Vec3 w1 = L * R * R * R / 3.0 * dirInt;                              // integral of w = r*dir
  const Vec3 sw = 0.5 * L * L * R * R * R / 3.0 * dirInt;                    // integral of s*w
  const Real cc = 0.5 * theta + 0.25 * std::sin(2 * theta);
  const Real ss = 0.5 * theta - 0.25 * std::sin(2 * theta);
  const Real cs = 0.5 * std::sin(theta) * std::sin(theta);
  const Mat3 dd = cc * e1 * e1.transpose() + ss * e2 * e2.transpose() + cs * (e1 * e2.transpose() + e2 * e1.transpose());
  Moments m;
  m.m0 = area * L;
  m.m1 = m.m0 * a + area * 0.5 * L * L * u + w1;
  m.m2 = m.m0 * a * a.transpose() + area * 0.5 * L * L * (a * u.transpose() + u * a.transpose()) +
         (a * w1.transpose() + w1 * a.transpose()) + area * L * L * L / 3.0 * u * u.transpose() +
         (u * sw.transpose() + sw * u.transpose()) + L * R * R * R * R / 4.0 * dd;
  return m;
}

// Gauss-Legendre nodes/weights on [0, 1].
template <int N>
struct Gauss {
  Real x[N], w[N];
  Gauss() {
    for (int i = 0; i < N; ++i) {  // Newton on P_N from the Chebyshev guess
      Real t = std::cos(kPi * (i + 0.75) / (N + 0.5)), dp = 1;
      for (int it = 0; it < 100; ++it) {
        Real p0 = 1, p1 = t;
        for (int k = 2; k <= N; ++k) {
          const Real p2 = ((2 * k - 1) * t * p1 - (k - 1) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        dp = N * (t * p1 - p0) / (t * t - 1);
        const Real dt = p1 / dp;
        t -= dt;
        if (std::abs(dt) < 1e-16) break;
      }
      x[i] = 0.5 * (1 - t);
      w[i] = 1.0 / ((1 - t * t) * dp * dp);
    }
  }
};

// A valley edge e (faces with normals n0, n1, c = n0.n1) ending at vertex V on a cap plane
// that it meets at a right angle (extruded shapes): the two ridge wedges along the cap edges
// that start at V overlap above the cap over the slab-overlap cross-section of the valley.
// In coordinates t0 = q.n0, t1 = q.n1 of the cross-section point q and height h along the
// cap normal nc, the overlap is 0 <= h <= sqrt(R^2 - max(t0, t1)^2). Its moments are
// integrated in each half (t0 >= t1 and t1 >= t0): the inner integral over the smaller t is
// a polynomial (3-point Gauss, exact), the outer one, with t = R sin(psi), a smooth
// trigonometric integrand (24-point Gauss, round-off accurate). Returns zero moments when the
// configuration is not this one (then the O(R^3) overlap is left in; see the header).
Moments reflexCornerOverlap(const SpheroPolyhedron& s, const CoreEdge& e, int vi, const Vec3& n0, const Vec3& n1,
                            Real c) {
  Moments m;
  const Vec3& V = s.vertices[vi];
  const Vec3 into = (s.vertices[vi == e.v0 ? e.v1 : e.v0] - V).normalized();  // along the valley, into the body
  const Vec3 nc = -into;
  const Real tol = 1e-9;
  bool cap0 = false, cap1 = false;
  for (int ei : s.vertexEdges[vi]) {
    const CoreEdge& r = s.edges[ei];
    if (!r.convex) continue;
    const Vec3& a = s.faces[r.f0].normal;
    const Vec3& b = s.faces[r.f1].normal;
    for (int k = 0; k < 2; ++k) {
      const Vec3& side = k ? b : a;
      const Vec3& cap = k ? a : b;
      if (1 - cap.dot(nc) > tol) continue;
      if (1 - side.dot(n0) < tol) cap0 = true;
      if (1 - side.dot(n1) < tol) cap1 = true;
    }
  }
  if (!cap0 || !cap1 || std::abs(n0.dot(nc)) > tol || std::abs(n1.dot(nc)) > tol) return m;
  static const Gauss<24> outer;
  static const Gauss<3> inner;
  const Real R = s.sweepRadius;
  const Real sinGamma = std::sqrt(1 - c * c);  // area element: dA = dt0 dt1 / sinGamma
  const Real lo = std::max(c, 0.0);           // in the half t0 >= t1: t1 from lo*t0 to t0
  for (int half = 0; half < 2; ++half) {
    const Vec3& na = half ? n1 : n0;  // the larger coordinate's normal
    const Vec3& nb = half ? n0 : n1;
    for (int i = 0; i < 24; ++i) {
      const Real psi = 0.5 * kPi * outer.x[i];
      const Real ta = R * std::sin(psi), H = R * std::cos(psi);
      const Real wOuter = 0.5 * kPi * outer.w[i] * R * std::cos(psi);  // dt_a = R cos(psi) dpsi
      for (int j = 0; j < 3; ++j) {
        const Real tb = ta * (lo + (1 - lo) * inner.x[j]);
        const Real w = wOuter * ta * (1 - lo) * inner.w[j] / sinGamma;
        const Vec3 p = V + ((ta - c * tb) * na + (tb - c * ta) * nb) / (1 - c * c);
        m.m0 += w * H;
        m.m1 += w * (H * p + 0.5 * H * H * nc);
        m.m2 += w * (H * p * p.transpose() + 0.5 * H * H * (p * nc.transpose() + nc * p.transpose()) +
                     H * H * H / 3.0 * nc * nc.transpose());
      }
    }
  }
  return m;
}

}  // namespace

Mat3 inertiaAbout(const Moments& m, const Vec3& c) {
  const Mat3 j = m.m2 - m.m1 * c.transpose() - c * m.m1.transpose() + m.m0 * c * c.transpose();
  return j.trace() * Mat3::Identity() - j;
}

Moments roundedBodyMoments(const SpheroPolyhedron& s) {
  const Real R = s.sweepRadius;
  Moments total = corePolyhedron(s);

  // Face slabs.
  std::vector<Real> cornerAngleSum(s.vertices.size(), 0.0);
  for (const CoreFace& f : s.faces) {
    std::vector<Vec3> poly;
    poly.reserve(f.loop.size());
    for (int vi : f.loop) poly.push_back(s.vertices[vi]);
    total += prism(poly, f.normal, R);
    const size_t n = f.loop.size();
    for (size_t i = 0; i < n; ++i) {
      const Vec3 a = poly[(i + n - 1) % n] - poly[i];
      const Vec3 b = poly[(i + 1) % n] - poly[i];
      cornerAngleSum[f.loop[i]] += std::atan2(a.cross(b).norm(), a.dot(b));
    }
  }

  // Edge wedges (ridges) and slab overlaps (valleys).
  for (const CoreEdge& e : s.edges) {
    const Vec3& p0 = s.vertices[e.v0];
    const Vec3& p1 = s.vertices[e.v1];
    const Real L = (p1 - p0).norm();
    const Vec3 u = (p1 - p0) / L;
    const Vec3& n0 = s.faces[e.f0].normal;
    const Vec3& n1 = s.faces[e.f1].normal;
    const Real c = std::max(-1.0, std::min(1.0, n0.dot(n1)));
    if (e.convex) {
      const Vec3 e2 = (n1 - c * n0).normalized();
      const Real theta = std::atan2(n0.cross(n1).norm(), c);
      total += wedge(p0, u, L, n0, e2, theta, R);
    } else {
      // Cross-section of the overlap of the two slabs, in the plane normal to the edge:
      // points q with q.n0 in [0,R] and q.n1 in [0,R] and on the edge side of both faces.
      // q(a,b) = ((a - c b) n0 + (b - c a) n1) / (1 - c^2) has q.n0 = a, q.n1 = b.
      auto at = [&](Real a, Real b) { return p0 + ((a - c * b) * n0 + (b - c * a) * n1) / (1.0 - c * c); };
      std::vector<Vec3> quad;
      // The free opening angle alpha of the valley satisfies c = n0.n1 = -cos(alpha).
      if (c <= 0) {  // alpha <= pi/2: the full rhombus
        quad = {p0, at(R, 0), at(R, R), at(0, R)};
      } else {  // obtuse opening: kite bounded by the rays along n0 and n1
        quad = {p0, p0 + R * n0, at(R, R), p0 + R * n1};
      }
      total -= prism(quad, u, L);
      total -= reflexCornerOverlap(s, e, e.v0, n0, n1, c);
      total -= reflexCornerOverlap(s, e, e.v1, n0, n1, c);
    }
  }

  // Vertex sectors over the normal cones of convex vertices.
  for (size_t vi = 0; vi < s.vertices.size(); ++vi) {
    if (s.vertexEdges[vi].empty()) continue;
    bool convexVertex = true;
    for (int ei : s.vertexEdges[vi]) convexVertex = convexVertex && s.edges[ei].convex;
    if (!convexVertex) continue;
    const Real omega = 2 * kPi - cornerAngleSum[vi];
    if (omega <= 0) continue;
    const Vec3& v = s.vertices[vi];
    Vec3 firstDir = Vec3::Zero();   // integral of w over the cone's spherical polygon
    Mat3 boundary = Mat3::Zero();   // sum over arcs of m W^T + W m^T
    for (int ei : s.vertexEdges[vi]) {
      const CoreEdge& e = s.edges[ei];
      const Vec3& n0 = s.faces[e.f0].normal;
      const Vec3& n1 = s.faces[e.f1].normal;
      const int other = (e.v0 == static_cast<int>(vi)) ? e.v1 : e.v0;
      const Vec3 m = (v - s.vertices[other]).normalized();  // arc plane normal, into the cone
      const Real gamma = std::atan2(n0.cross(n1).norm(), n0.dot(n1));
      const Vec3 W = std::tan(0.5 * gamma) * (n0 + n1);  // integral of w along the arc
      firstDir += 0.5 * gamma * m;
      boundary += m * W.transpose() + W * m.transpose();
    }
    const Mat3 secondDir = omega / 3.0 * Mat3::Identity() + boundary / 6.0;
    Moments m;
    m.m0 = omega * R * R * R / 3.0;
    const Vec3 mw = R * R * R * R / 4.0 * firstDir;
    m.m1 = m.m0 * v + mw;
    m.m2 = m.m0 * v * v.transpose() + v * mw.transpose() + mw * v.transpose() + std::pow(R, 5) / 5.0 * secondDir;
    total += m;
  }
  return total;
}

}  // namespace sdem
}  // namespace mpmsdem
