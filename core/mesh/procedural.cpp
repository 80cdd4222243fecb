// Procedural meshes: spec "procedural:NAME?key=value&key=value". All are generated in double
// (Mesh::positionsDouble), y up unless noted, counter-clockwise (outward-facing) triangles.
//
//   spheres  tris=N (default 200000, at least 100): a grid of UV spheres of varying radii
//            sitting on the ground plane y=0 (a 12x12 square of 2 triangles). The grid spans
//            about 10 units centred on the origin; each sphere's segments and rings are chosen
//            so the total triangle count (ground included) is within 1% of N.
//   default  the same as spheres with its defaults (accepts the same keys).
//   sphere   radius=R (default 1), segments=S (longitude, default 64, >= 3), rings=Q (latitude
//            bands, default 32, >= 2), centre cx, cy, cz (default 0). Poles on the y axis;
//            S*(Q-1)+2 vertices, 2*S*(Q-1) triangles. All vertices lie on the sphere; every
//            point of the triangles lies inside it, at least R*cos(pi/(2Q))*cos(pi/S) from the
//            centre, so the tessellation deviates from the true sphere by at most the chord
//            sagitta R*(1 - cos(pi/(2Q))*cos(pi/S)) (attained at the equator band).
//   quad     size=S (default 2), z=Z (default 0): the square [-S/2, S/2]^2 in the plane z=Z
//            as 2 triangles facing +z; vertices (-h,-h), (h,-h), (h,h), (-h,h).
//   cube     size=S (default 1): closed cube [-S/2, S/2]^3, 8 shared vertices, 12 triangles.
//   city     no keys: about 20x20 units of ground (y=0) with rows of closed boxes of different
//            heights and some tall 24-sided columns (closed cylinders).
#include <cmath>
#include <cstdlib>
#include <map>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "core/util/huge_pages.h"
#include "core/util/parallel.h"
#include "core/util/sampling.h"
#include "core/util/units.h"

namespace aperture {
namespace {

using Params = std::map<std::string, double>;

/// Parses "k=v&k=v" into `defaults`, rejecting keys not present there.
void parseParams(const std::string& spec, const std::string& name, const std::string& query,
                 Params& params) {
  size_t pos = 0;
  while (pos < query.size()) {
    size_t amp = query.find('&', pos);
    if (amp == std::string::npos) amp = query.size();
    std::string kv = query.substr(pos, amp - pos);
    pos = amp + 1;
    if (kv.empty()) continue;
    size_t eq = kv.find('=');
    std::string key = kv.substr(0, eq);
    auto it = params.find(key);
    if (it == params.end()) {
      std::string known;
      for (const auto& p : params) known += (known.empty() ? "" : ", ") + p.first;
      throw Error(cat(spec, ": unknown key '", key, "' for procedural:", name,
                      " (known keys: ", known.empty() ? "none" : known, ")"));
    }
    if (eq == std::string::npos)
      throw Error(cat(spec, ": key '", key, "' needs a value (", key, "=VALUE)"));
    std::string value = kv.substr(eq + 1);
    char* endp = nullptr;
    double v = std::strtod(value.c_str(), &endp);
    if (value.empty() || *endp != '\0' || !std::isfinite(v))
      throw Error(cat(spec, ": value of '", key, "' is not a number: '", value, "'"));
    it->second = v;
  }
}

long asCount(const std::string& spec, const char* key, double v, long lo, long hi) {
  if (v != std::floor(v) || v < double(lo) || v > double(hi))
    throw Error(cat(spec, ": ", key, "=", v, " must be a whole number in [", lo, ", ", hi, "]"));
  return long(v);
}

/// Appends to a mesh under construction; vertices are double triples.
struct Builder {
  std::vector<double>& pos;
  LargeBuffer<uint32_t>& idx;
  uint32_t addVertex(double x, double y, double z) {
    pos.push_back(x);
    pos.push_back(y);
    pos.push_back(z);
    return uint32_t(pos.size() / 3 - 1);
  }
  void tri(uint32_t a, uint32_t b, uint32_t c) {
    idx.push_back(a);
    idx.push_back(b);
    idx.push_back(c);
  }
  void quad(uint32_t a, uint32_t b, uint32_t c, uint32_t d) {  // counter-clockwise a b c d
    tri(a, b, c);
    tri(a, c, d);
  }
};

size_t sphereVertices(long segments, long rings) { return size_t(segments * (rings - 1) + 2); }
size_t sphereTriangles(long segments, long rings) { return size_t(2 * segments * (rings - 1)); }

/// Writes a UV sphere's vertices at pos[3*v0..] and its triangles at idx[3*t0..].
void writeSphere(double* pos, uint32_t* idx, uint32_t v0, glm::dvec3 c, double r, long segments,
                 long rings) {
  size_t v = 0;
  auto put = [&](double x, double y, double z) {
    pos[3 * v] = c.x + x;
    pos[3 * v + 1] = c.y + y;
    pos[3 * v + 2] = c.z + z;
    ++v;
  };
  put(0, r, 0);
  for (long j = 1; j < rings; ++j) {
    double theta = kPi * double(j) / double(rings);
    for (long k = 0; k < segments; ++k) {
      double phi = 2 * kPi * double(k) / double(segments);
      put(r * std::sin(theta) * std::cos(phi), r * std::cos(theta),
          -r * std::sin(theta) * std::sin(phi));
    }
  }
  put(0, -r, 0);
  const uint32_t north = v0, south = v0 + uint32_t(v) - 1;
  auto ring = [&](long j, long k) { return v0 + 1 + uint32_t((j - 1) * segments + k % segments); };
  size_t t = 0;
  auto tri = [&](uint32_t a, uint32_t b, uint32_t d) {
    idx[3 * t] = a;
    idx[3 * t + 1] = b;
    idx[3 * t + 2] = d;
    ++t;
  };
  for (long k = 0; k < segments; ++k) tri(north, ring(1, k), ring(1, k + 1));
  for (long j = 1; j + 1 < rings; ++j)
    for (long k = 0; k < segments; ++k) {
      tri(ring(j, k), ring(j + 1, k), ring(j + 1, k + 1));
      tri(ring(j, k), ring(j + 1, k + 1), ring(j, k + 1));
    }
  for (long k = 0; k < segments; ++k) tri(south, ring(rings - 1, k + 1), ring(rings - 1, k));
}

/// A sphere spec's tessellation, radius and centre, validated.
struct SphereShape {
  long segments = 0, rings = 0;
  double radius = 1;
  glm::dvec3 centre{0.0};
};

SphereShape sphereShape(const std::string& spec, const Params& p) {
  SphereShape s;
  s.segments = asCount(spec, "segments", p.at("segments"), 3, 1 << 16);
  s.rings = asCount(spec, "rings", p.at("rings"), 2, 1 << 16);
  s.radius = p.at("radius");
  if (!(s.radius > 0)) throw Error(cat(spec, ": radius=", s.radius, " must be positive"));
  if (sphereVertices(s.segments, s.rings) > (size_t(1) << 31))
    throw Error(cat(spec, ": segments*rings is too large"));
  s.centre = {p.at("cx"), p.at("cy"), p.at("cz")};
  return s;
}

Mesh makeSphere(const SphereShape& s) {
  Mesh m;
  m.vertexCount = sphereVertices(s.segments, s.rings);
  resizeOnHugePages(m.positionsDouble, 3 * m.vertexCount);
  resizeOnHugePages(m.indices, 3 * sphereTriangles(s.segments, s.rings));
  writeSphere(m.positionsDouble.data(), m.indices.data(), 0, s.centre, s.radius, s.segments,
              s.rings);
  return m;
}

/// Picks (segments, rings) with 2*segments*(rings-1) as close as possible to `target`,
/// preferring segments near 2*(rings-1) (roughly square quads).
void chooseTessellation(double target, long& segments, long& rings) {
  double best = 1e300;
  long s0 = std::max(3L, long(std::sqrt(target) * 0.5));
  long s1 = std::max(s0 + 1, long(std::sqrt(target) * 1.5) + 2);
  for (long s = s0; s <= s1; ++s) {
    long bands = std::max(1L, std::lround(target / (2.0 * double(s))));
    double err = std::fabs(2.0 * double(s) * double(bands) - target);
    double shape = std::fabs(std::log(double(s) / (2.0 * double(bands))));
    double score = err + 1e-3 * shape;
    if (score < best) {
      best = score;
      segments = s;
      rings = bands + 1;
    }
  }
}

/// Uniform in [0, 1) from an integer: the sizes and heights of the scenes' objects.
double hash01(uint32_t i) { return double(hash32(i)) / 4294967296.0; }

/// The spheres scene's layout: a g x g grid of spheres after the ground; sphere i has
/// segs[i] x rings[i] and its vertices and triangles start at vOff[i] and tOff[i]. The last
/// offsets are the mesh's vertex and triangle counts.
struct SpheresPlan {
  long grid = 1;
  std::vector<long> segs, rings;
  std::vector<size_t> vOff, tOff;
};

SpheresPlan planSpheres(const std::string& spec, const Params& p) {
  const long tris = asCount(spec, "tris", p.at("tris"), 100, 400000000);
  SpheresPlan plan;
  // More spheres for larger budgets, capped to keep them detailed.
  plan.grid = std::clamp(std::lround(std::sqrt(double(tris) / 5000.0)), 1L, 20L);
  const size_t count = size_t(plan.grid * plan.grid);
  plan.segs.resize(count);
  plan.rings.resize(count);
  plan.vOff.assign(count + 1, 4);  // the ground's 4 vertices and 2 triangles come first
  plan.tOff.assign(count + 1, 2);
  for (size_t i = 0; i < count; ++i) {
    // Each sphere aims at an equal share of what is left, so rounding errors do not add up.
    const double target = double(size_t(tris) - plan.tOff[i]) / double(count - i);
    chooseTessellation(target, plan.segs[i], plan.rings[i]);
    plan.vOff[i + 1] = plan.vOff[i] + sphereVertices(plan.segs[i], plan.rings[i]);
    plan.tOff[i + 1] = plan.tOff[i] + sphereTriangles(plan.segs[i], plan.rings[i]);
  }
  if (plan.vOff.back() > (size_t(1) << 32) - 1)
    throw Error(cat(spec, ": too many vertices for 32-bit indices"));
  return plan;
}

Mesh makeSpheres(const SpheresPlan& plan) {
  Mesh m;
  m.vertexCount = plan.vOff.back();
  resizeOnHugePages(m.positionsDouble, 3 * m.vertexCount);
  resizeOnHugePages(m.indices, 3 * plan.tOff.back());
  const double h = 6.0;
  const double ground[12] = {-h, 0, h, h, 0, h, h, 0, -h, -h, 0, -h};
  std::copy(ground, ground + 12, m.positionsDouble.begin());
  const uint32_t groundIdx[6] = {0, 1, 2, 0, 2, 3};
  std::copy(groundIdx, groundIdx + 6, m.indices.begin());
  const long g = plan.grid;
  const double spacing = 10.0 / double(g);
  parallelFor(size_t(g * g), 16, [&](size_t first, size_t last) {
    for (long i = long(first); i != long(last); ++i) {
      long row = i / g, col = i % g;
      double r = spacing * 0.45 * (0.35 + 0.65 * hash01(uint32_t(i)));
      glm::dvec3 c(-5.0 + spacing * (double(col) + 0.5), r, -5.0 + spacing * (double(row) + 0.5));
      size_t k = size_t(i);
      uint32_t* idx = m.indices.data() + 3 * plan.tOff[k];
      writeSphere(m.positionsDouble.data() + 3 * plan.vOff[k], idx, uint32_t(plan.vOff[k]), c, r,
                  plan.segs[k], plan.rings[k]);
    }
  });
  return m;
}

Mesh makeQuad(const Params& p) {
  Mesh m;
  Builder b{m.positionsDouble, m.indices};
  double h = p.at("size") / 2, z = p.at("z");
  uint32_t v0 = b.addVertex(-h, -h, z), v1 = b.addVertex(h, -h, z);
  uint32_t v2 = b.addVertex(h, h, z), v3 = b.addVertex(-h, h, z);
  b.quad(v0, v1, v2, v3);
  m.vertexCount = 4;
  return m;
}

/// Closed axis-aligned box [lo, hi] with 8 shared vertices and outward triangles.
void addBox(Builder& b, glm::dvec3 lo, glm::dvec3 hi) {
  uint32_t v[8];
  for (int i = 0; i < 8; ++i)
    v[i] = b.addVertex(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
  b.quad(v[0], v[4], v[6], v[2]);  // -x
  b.quad(v[1], v[3], v[7], v[5]);  // +x
  b.quad(v[0], v[1], v[5], v[4]);  // -y
  b.quad(v[2], v[6], v[7], v[3]);  // +y
  b.quad(v[0], v[2], v[3], v[1]);  // -z
  b.quad(v[4], v[5], v[7], v[6]);  // +z
}

/// Closed vertical cylinder standing on y=0 at (x, z).
void addColumn(Builder& b, double x, double z, double radius, double height, int sides) {
  uint32_t bottom = b.addVertex(x, 0, z), top = b.addVertex(x, height, z);
  uint32_t first = uint32_t(b.pos.size() / 3);
  for (int k = 0; k < sides; ++k) {
    double phi = 2 * kPi * k / sides;
    double dx = radius * std::cos(phi), dz = -radius * std::sin(phi);
    b.addVertex(x + dx, 0, z + dz);
    b.addVertex(x + dx, height, z + dz);
  }
  for (int k = 0; k < sides; ++k) {
    uint32_t b0 = first + 2 * k, t0 = b0 + 1;
    uint32_t b1 = first + 2 * ((k + 1) % sides), t1 = b1 + 1;
    b.quad(b0, b1, t1, t0);
    b.tri(top, t0, t1);
    b.tri(bottom, b1, b0);
  }
}

Mesh makeCity() {
  Mesh m;
  Builder b{m.positionsDouble, m.indices};
  uint32_t g[4];
  const double h = 11.0;
  g[0] = b.addVertex(-h, 0, h);
  g[1] = b.addVertex(h, 0, h);
  g[2] = b.addVertex(h, 0, -h);
  g[3] = b.addVertex(-h, 0, -h);
  b.quad(g[0], g[1], g[2], g[3]);
  // Four rows of boxes along x, with streets between the rows.
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 7; ++col) {
      uint32_t id = uint32_t(row * 7 + col);
      double x = -8.4 + 2.8 * col, z = -7.5 + 5.0 * row;
      double w = 1.0 + 0.8 * hash01(id * 3), d = 1.2 + 1.2 * hash01(id * 3 + 1);
      double height = 0.8 + 5.0 * hash01(id * 3 + 2) * hash01(id * 3 + 2);
      addBox(b, {x - w / 2, 0, z - d / 2}, {x + w / 2, height, z + d / 2});
    }
  // Tall columns in the streets.
  for (int i = 0; i < 6; ++i) {
    double x = -7.5 + 3.0 * i, z = (i % 2 ? -5.0 : 5.0);
    addColumn(b, x, z, 0.35, 7.0 + 2.0 * hash01(uint32_t(100 + i)), 24);
  }
  m.vertexCount = m.positionsDouble.size() / 3;
  return m;
}

Mesh makeCube(const Params& p) {
  Mesh m;
  Builder b{m.positionsDouble, m.indices};
  double h = p.at("size") / 2;
  addBox(b, glm::dvec3(-h), glm::dvec3(h));
  m.vertexCount = 8;
  return m;
}

/// A procedural spec split into its name and its parameters (defaults filled in).
struct ProceduralSpec {
  std::string name;
  Params params;
};

ProceduralSpec parseSpec(const std::string& spec) {
  const std::string prefix = "procedural:";
  if (spec.rfind(prefix, 0) != 0)
    throw Error(cat(spec, ": a procedural spec starts with '", prefix, "'"));
  std::string rest = spec.substr(prefix.size());
  size_t q = rest.find('?');
  ProceduralSpec s;
  s.name = rest.substr(0, q);
  std::string query = q == std::string::npos ? "" : rest.substr(q + 1);
  if (s.name == "spheres" || s.name == "default") {
    s.params = {{"tris", 200000}};
  } else if (s.name == "sphere") {
    s.params = {{"radius", 1}, {"segments", 64}, {"rings", 32}, {"cx", 0}, {"cy", 0}, {"cz", 0}};
  } else if (s.name == "quad") {
    s.params = {{"size", 2}, {"z", 0}};
  } else if (s.name == "cube") {
    s.params = {{"size", 1}};
  } else if (s.name != "city") {
    throw Error(cat(spec, ": unknown procedural mesh '", s.name,
                    "' (known: spheres, default, sphere, quad, cube, city)"));
  }
  parseParams(spec, s.name, query, s.params);
  if (s.params.count("size") && !(s.params["size"] > 0))
    throw Error(cat(spec, ": size=", s.params["size"], " must be positive"));
  return s;
}

bool isSpheresScene(const ProceduralSpec& s) { return s.name == "spheres" || s.name == "default"; }

Mesh generate(const std::string& spec, const ProceduralSpec& s) {
  if (isSpheresScene(s)) return makeSpheres(planSpheres(spec, s.params));
  if (s.name == "sphere") return makeSphere(sphereShape(spec, s.params));
  if (s.name == "quad") return makeQuad(s.params);
  if (s.name == "cube") return makeCube(s.params);
  return makeCity();
}

}  // namespace

Mesh makeProcedural(const std::string& spec) {
  Mesh m = generate(spec, parseSpec(spec));
  m.name = spec;
  m.stats.sourceFaces = m.triangleCount();
  return m;
}

MeshCounts proceduralMeshCounts(const std::string& spec) {
  const ProceduralSpec s = parseSpec(spec);
  if (isSpheresScene(s)) {
    const SpheresPlan plan = planSpheres(spec, s.params);
    return {plan.vOff.back(), plan.tOff.back()};
  }
  if (s.name == "sphere") {
    const SphereShape shape = sphereShape(spec, s.params);
    return {sphereVertices(shape.segments, shape.rings),
            sphereTriangles(shape.segments, shape.rings)};
  }
  // The others are a few hundred triangles at most: generate them and count.
  const Mesh m = generate(spec, s);
  return {m.vertexCount, m.triangleCount()};
}

}  // namespace aperture
