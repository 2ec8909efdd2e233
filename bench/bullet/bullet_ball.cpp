// bullet_ball: the Bullet side of issue 6's "time to solution" comparison.
//
// A 2562-vertex icosphere (level 4 subdivided icosahedron) of 1 m diameter and 1 kg, as a
// Bullet btSoftBody (links on the mesh edges + Bullet's bending constraints, i.e. more links
// between the vertices --bending D edges apart), dropped with its lowest point 1.5 m
// above a static ground plane (btStaticPlaneShape, y = 0), gravity 9.81, simulated 2 s.
// By default pressure and volume conservation are OFF (kPR = kVC = 0) and pose matching is off
// (kMT = 0): the ball keeps its volume with its links alone, as springy's with its struts and
// hinges. --kpr K turns on Bullet's pressure model (btSoftBody::Config::kPR, its pressure
// coefficient: a force on every face along its normal, in proportion to kPR and the face's area
// over the enclosed volume), the counterpart of springy's enclosed gas (bench/drop_2562_gas.toml).
//
// The step dt and the position-solver iteration count (piterations) come from the command
// line. Every step the enclosed volume (signed volume of the closed triangle mesh, divergence
// theorem) is measured; the program reports the minimum and end volume ratios, the wall time
// of the simulation loop (steady_clock, setup excluded) and ns per vertex per step, and exits
// non-zero if the volume ratio ever fell below --min-volume (0.95), a position is not finite,
// a vertex went more than --max-penetration (0.05 m, a tenth of the radius) below the ground,
// or the ball grew past 10x its size.
//
//   bullet_ball --dt 0.004 --piterations 10 [--duration 2] [--klst 1] [--bend-klst 1]
//               [--bending 2] [--kdp 0] [--kpr 0] [--margin 0.01] [--min-volume 0.95]
//               [--max-penetration 0.05] [--quiet]
//
// Output: a few human-readable lines, then one `result` line of key=value pairs (for scripts).
#include <btBulletDynamicsCommon.h>
#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace {

struct Mesh {
  std::vector<std::array<double, 3>> positions;
  std::vector<std::array<int, 3>> triangles;  // counter-clockwise seen from outside
};

std::array<double, 3> unit(std::array<double, 3> p) {
  const double l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  return {p[0] / l, p[1] / l, p[2] / l};
}

// The regular icosahedron (vertices on the three golden rectangles), each subdivision
// splitting every triangle into four at its edge midpoints pushed out to the sphere:
// 10 * 4^level + 2 vertices. The same standard construction as springy's `icosphere`, so the
// two simulators start from the same vertices.
Mesh icosphere(double radius, int level) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  Mesh m;
  m.positions = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : m.positions) p = unit(p);
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> midpoints;
    auto midpoint = [&](int a, int b) {
      const std::pair<int, int> key = std::minmax(a, b);
      auto [it, inserted] = midpoints.try_emplace(key, static_cast<int>(m.positions.size()));
      if (inserted) {
        const auto& pa = m.positions[static_cast<std::size_t>(a)];
        const auto& pb = m.positions[static_cast<std::size_t>(b)];
        m.positions.push_back(unit({pa[0] + pb[0], pa[1] + pb[1], pa[2] + pb[2]}));
      }
      return it->second;
    };
    std::vector<std::array<int, 3>> finer;
    finer.reserve(m.triangles.size() * 4);
    for (const auto& tri : m.triangles) {
      const int ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]), ca = midpoint(tri[2], tri[0]);
      finer.push_back({tri[0], ab, ca});
      finer.push_back({tri[1], bc, ab});
      finer.push_back({tri[2], ca, bc});
      finer.push_back({ab, bc, ca});
    }
    m.triangles = std::move(finer);
  }
  for (auto& p : m.positions) p = {p[0] * radius, p[1] * radius, p[2] * radius};
  return m;
}

// Signed volume enclosed by the closed mesh over the soft body's current node positions
// (node i is mesh vertex i: CreateFromTriMesh keeps the vertex order). Summed in double.
double enclosedVolume(const btSoftBody& body, const std::vector<std::array<int, 3>>& triangles) {
  double v = 0.0;
  for (const auto& tri : triangles) {
    const btVector3& a = body.m_nodes[tri[0]].m_x;
    const btVector3& b = body.m_nodes[tri[1]].m_x;
    const btVector3& c = body.m_nodes[tri[2]].m_x;
    const double ax = a.x(), ay = a.y(), az = a.z(), bx = b.x(), by = b.y(), bz = b.z();
    const double cx = c.x(), cy = c.y(), cz = c.z();
    v += ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx);
  }
  return v / 6.0;
}

// Bullet's bending constraints: one link (flagged m_bbending) between every pair of nodes
// exactly `distance` edges apart in the link graph, as btSoftBody::generateBendingConstraints
// makes them. That function finds the distances with Floyd-Warshall over an n x n matrix
// (O(n^3): 9 s of setup for 2562 nodes at distance >= 3); a breadth-first search from every
// node gives the same pairs in milliseconds (--bullet-bending uses Bullet's own).
int appendBendingLinks(btSoftBody& body, int distance, btSoftBody::Material* material) {
  const int n = body.m_nodes.size();
  std::vector<std::vector<int>> adjacent(static_cast<std::size_t>(n));
  auto index = [&body](const btSoftBody::Node* node) { return static_cast<int>(node - &body.m_nodes[0]); };
  for (int i = 0; i < body.m_links.size(); ++i) {
    const int a = index(body.m_links[i].m_n[0]), b = index(body.m_links[i].m_n[1]);
    adjacent[static_cast<std::size_t>(a)].push_back(b);
    adjacent[static_cast<std::size_t>(b)].push_back(a);
  }
  std::vector<std::pair<int, int>> pairs;
  std::vector<int> depth(static_cast<std::size_t>(n), -1), frontier, next, touched;
  for (int s = 0; s < n; ++s) {
    depth[static_cast<std::size_t>(s)] = 0;
    touched = {s};
    frontier = {s};
    for (int d = 1; d <= distance && !frontier.empty(); ++d) {
      next.clear();
      for (int u : frontier) {
        for (int v : adjacent[static_cast<std::size_t>(u)]) {
          if (depth[static_cast<std::size_t>(v)] >= 0) continue;
          depth[static_cast<std::size_t>(v)] = d;
          touched.push_back(v);
          next.push_back(v);
          if (d == distance && v > s) pairs.emplace_back(s, v);
        }
      }
      std::swap(frontier, next);
    }
    for (int v : touched) depth[static_cast<std::size_t>(v)] = -1;
  }
  std::sort(pairs.begin(), pairs.end());  // Bullet's order: by the smaller index, then the larger
  for (const auto& [a, b] : pairs) {
    body.appendLink(b, a, material);  // the larger index first, as Bullet
    body.m_links[body.m_links.size() - 1].m_bbending = -1;  // a 1-bit int: Bullet's "= 1" stores -1 too
  }
  return static_cast<int>(pairs.size());
}

struct Options {
  double dt = 1.0 / 240.0;
  int piterations = 10;
  double duration = 2.0;
  double klst = 1.0;      // edge links' linear stiffness [0, 1]
  double bendKlst = 1.0;  // bending links' linear stiffness [0, 1]
  int bending = 2;        // generateBendingConstraints distance (0: no bending links)
  double kdp = 0.0;       // velocity damping [0, 1]
  double kpr = 0.0;       // pressure coefficient (0: no pressure)
  double kdf = 0.3;       // dynamic friction against the ground (springy's plane: 0.3)
  double margin = 0.01;   // collision margin [m] (Bullet's soft-body default is 0.25 m)
  double minVolume = 0.95;
  double maxPenetration = 0.05;  // [m] below the plane
  bool bulletBending = false;  // Bullet's generateBendingConstraints instead of the BFS
  bool quiet = false;
};

[[noreturn]] void usage(const char* argv0) {
  std::fprintf(stderr,
               "usage: %s [--dt S] [--piterations N] [--duration S] [--klst K] [--bend-klst K] [--bending D]\n"
               "          [--kdp K] [--kpr K] [--kdf K] [--margin M] [--min-volume F] [--max-penetration M]\n"
               "          [--bullet-bending] [--quiet]\n",
               argv0);
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> const char* {
      if (i + 1 >= argc) usage(argv[0]);
      return argv[++i];
    };
    auto number = [&]() {
      const char* s = value();
      char* end = nullptr;
      const double x = std::strtod(s, &end);
      if (end == s || *end != '\0' || !std::isfinite(x)) usage(argv[0]);
      return x;
    };
    if (a == "--dt") o.dt = number();
    else if (a == "--piterations") o.piterations = static_cast<int>(number());
    else if (a == "--duration") o.duration = number();
    else if (a == "--klst") o.klst = number();
    else if (a == "--bend-klst") o.bendKlst = number();
    else if (a == "--bending") o.bending = static_cast<int>(number());
    else if (a == "--kdp") o.kdp = number();
    else if (a == "--kdf") o.kdf = number();
    else if (a == "--kpr") o.kpr = number();
    else if (a == "--margin") o.margin = number();
    else if (a == "--min-volume") o.minVolume = number();
    else if (a == "--max-penetration") o.maxPenetration = number();
    else if (a == "--quiet") o.quiet = true;
    else if (a == "--bullet-bending") o.bulletBending = true;
    else usage(argv[0]);
  }
  if (!(o.dt > 0) || o.piterations < 1 || !(o.duration > 0)) usage(argv[0]);
  return o;
}


// The ball's vertices as Bullet takes them, placed so that its lowest vertex is dropHeight [m]
// above the ground, and its triangles' corners.
struct PlacedBall {
  std::vector<btScalar> vertices;  // x, y, z per vertex
  std::vector<int> indices;        // three per triangle
  double minY = 0.0;               // [m] the lowest vertex, relative to the centre
  double centerY = 0.0;            // [m] the centre's height
};

PlacedBall placeBall(const Mesh& mesh, double dropHeight) {
  PlacedBall ball;
  for (const auto& p : mesh.positions) ball.minY = std::min(ball.minY, p[1]);
  ball.centerY = dropHeight - ball.minY;
  for (const auto& p : mesh.positions) {
    ball.vertices.push_back(static_cast<btScalar>(p[0]));
    ball.vertices.push_back(static_cast<btScalar>(p[1] + ball.centerY));
    ball.vertices.push_back(static_cast<btScalar>(p[2]));
  }
  for (const auto& t : mesh.triangles) ball.indices.insert(ball.indices.end(), t.begin(), t.end());
  return ball;
}

// The world: rigid + soft, the usual Bullet set-up, with a static ground, the plane y = 0.
// Members are destroyed in reverse order: the ground first, the world before what it uses.
struct BulletWorld {
  std::unique_ptr<btSoftBodyRigidBodyCollisionConfiguration> collisionConfig;
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  std::unique_ptr<btDbvtBroadphase> broadphase;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
  std::unique_ptr<btSoftRigidDynamicsWorld> world;
  std::unique_ptr<btStaticPlaneShape> groundShape;
  std::unique_ptr<btRigidBody> ground;
};

void makeWorld(BulletWorld& w, double gravity) {
  w.collisionConfig = std::make_unique<btSoftBodyRigidBodyCollisionConfiguration>();
  w.dispatcher = std::make_unique<btCollisionDispatcher>(w.collisionConfig.get());
  w.broadphase = std::make_unique<btDbvtBroadphase>();
  w.solver = std::make_unique<btSequentialImpulseConstraintSolver>();
  w.world = std::make_unique<btSoftRigidDynamicsWorld>(w.dispatcher.get(), w.broadphase.get(), w.solver.get(),
                                                       w.collisionConfig.get());
  const btVector3 g(0, static_cast<btScalar>(-gravity), 0);
  w.world->setGravity(g);
  btSoftBodyWorldInfo& info = w.world->getWorldInfo();
  info.m_gravity = g;
  info.air_density = 0;  // no aerodynamics (springy's scene has no drag either)
  info.m_sparsesdf.Initialize();

  // Static ground: the plane y = 0, friction 1 so the contact friction is the body's kDF.
  w.groundShape = std::make_unique<btStaticPlaneShape>(btVector3(0, 1, 0), 0);
  w.groundShape->setMargin(0);  // contact at the plane itself (plus the body's margin)
  btRigidBody::btRigidBodyConstructionInfo groundInfo(0, nullptr, w.groundShape.get());
  groundInfo.m_friction = 1;
  w.ground = std::make_unique<btRigidBody>(groundInfo);
  w.world->addRigidBody(w.ground.get());
}

// The soft body's links: the mesh edges' and the bending links (Bullet's bending constraints are
// links between vertices `bending` edges apart).
struct LinkCounts {
  int edges = 0, bending = 0;
};

// The soft body's materials and solver settings from the options: kLST of the edge and bending
// links, Bullet's bending constraints (or the same links by breadth-first search), pressure,
// damping and friction; no volume conservation or pose matching.
LinkCounts configureBody(btSoftBody& body, const Options& opt, double mass) {
  LinkCounts links;
  btSoftBody::Material* edges = body.m_materials[0];
  edges->m_kLST = static_cast<btScalar>(opt.klst);
  edges->m_kAST = 1;
  edges->m_kVST = 1;
  links.edges = body.m_links.size();
  if (opt.bending > 0) {
    btSoftBody::Material* bend = body.appendMaterial();
    bend->m_kLST = static_cast<btScalar>(opt.bendKlst);
    bend->m_kAST = 1;
    bend->m_kVST = 1;
    links.bending = opt.bulletBending ? body.generateBendingConstraints(opt.bending, bend)
                                      : appendBendingLinks(body, opt.bending, bend);
  }
  body.randomizeConstraints();  // Bullet's recommended Gauss-Seidel ordering
  btSoftBody::Config& cfg = body.m_cfg;
  cfg.piterations = opt.piterations;
  cfg.viterations = 0;
  cfg.diterations = 0;
  cfg.kPR = static_cast<btScalar>(opt.kpr);  // 0: no pressure
  cfg.kVC = 0;  // no volume conservation
  cfg.kMT = 0;  // no pose matching
  cfg.kDP = static_cast<btScalar>(opt.kdp);
  cfg.kDF = static_cast<btScalar>(opt.kdf);
  cfg.kDG = 0;
  cfg.kLF = 0;
  cfg.collisions = btSoftBody::fCollision::SDF_RS;  // vertices against rigid shapes (the default)
  body.getCollisionShape()->setMargin(static_cast<btScalar>(opt.margin));
  body.setTotalMass(static_cast<btScalar>(mass), /*fromfaces=*/true);  // mass by area, as springy
  return links;
}

// What the run measured, step by step, and how it ended.
struct RunRecord {
  double maxStrain = 0.0;  // largest |l - l0| / l0 of a mesh edge over the run (springy check's "max strain")
  double minRatio = 1.0, maxRatio = 1.0, ratio = 1.0;  // volume over rest volume: least, most, last
  double lowest = 0.0, endLowest = 0.0;                // [m] the lowest vertex's height: least, last
  double stepSeconds = 0.0;                            // [s] in stepSimulation
  double wall = 0.0;                                   // [s] of wall time in the simulation loop
  // The bounce: the centre's highest point (the bounding box's, at hand) from t = 0.7 s on, when
  // the ball, which lands at 0.55 s, has left the ground again (or not): the first bounce's apex.
  double apex = -std::numeric_limits<double>::infinity();
  long failedStep = -1;
  std::string failure;
};

// The largest strain of a mesh edge's link now (randomizeConstraints shuffled the links, so the
// bending links are skipped by their flag).
double largestEdgeStrain(const btSoftBody& body) {
  double strain = 0.0;
  for (int k = 0; k < body.m_links.size(); ++k) {
    const btSoftBody::Link& link = body.m_links[k];
    if (link.m_bbending) continue;
    const double l = static_cast<double>((link.m_n[1]->m_x - link.m_n[0]->m_x).length());
    strain = std::max(strain, std::fabs(l - static_cast<double>(link.m_rl)) / static_cast<double>(link.m_rl));
  }
  return strain;
}

// Measures the state after step s (time s dt [s]) into the record; the failure it shows, if any
// (not finite, the volume ratio below the limit, sunk into the ground, grown past 10x its size).
void measureStep(const btSoftBody& body, const Mesh& mesh, double restVolume, const Options& opt, double radius,
                 long s, btScalar dt, RunRecord& run) {
  run.ratio = enclosedVolume(body, mesh.triangles) / restVolume;
  run.maxStrain = std::max(run.maxStrain, largestEdgeStrain(body));
  run.minRatio = std::min(run.minRatio, run.ratio);
  run.maxRatio = std::max(run.maxRatio, run.ratio);
  btVector3 lo = body.m_nodes[0].m_x, hi = lo;
  bool finite = std::isfinite(run.ratio);
  for (int i = 0; i < body.m_nodes.size(); ++i) {
    const btVector3& x = body.m_nodes[i].m_x;
    finite = finite && std::isfinite(x.x()) && std::isfinite(x.y()) && std::isfinite(x.z());
    lo.setMin(x);
    hi.setMax(x);
  }
  run.endLowest = static_cast<double>(lo.y());
  run.lowest = std::min(run.lowest, run.endLowest);
  if (static_cast<double>(s) * dt >= 0.7) run.apex = std::max(run.apex, 0.5 * static_cast<double>(lo.y() + hi.y()));
  if (!finite) {
    run.failure = "a position or the volume is not finite";
  } else if (run.ratio < opt.minVolume) {
    run.failure = "volume ratio " + std::to_string(run.ratio) + " below " + std::to_string(opt.minVolume);
  } else if (lo.y() < -opt.maxPenetration) {
    run.failure = "sank into the ground (lowest vertex y = " + std::to_string(lo.y()) + " m)";
  } else if ((hi - lo).length() > 10.0 * 2.0 * radius * std::sqrt(3.0)) {
    run.failure = "grew past 10x its size";
  }
}

// The simulation loop: `steps` steps of dt [s], each measured, until the first failure. The
// lowest vertex starts at the centre's height `centerY` [m] (any vertex is lower).
RunRecord simulate(btSoftRigidDynamicsWorld& world, const btSoftBody& body, const Mesh& mesh, double restVolume,
                   const Options& opt, double radius, long steps, btScalar dt, double centerY) {
  RunRecord run;
  run.lowest = run.endLowest = centerY;
  const auto loopStart = std::chrono::steady_clock::now();
  for (long s = 1; s <= steps; ++s) {
    const auto t0 = std::chrono::steady_clock::now();
    world.stepSimulation(dt, 0);  // maxSubSteps 0: exactly one step of dt
    run.stepSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    measureStep(body, mesh, restVolume, opt, radius, s, dt, run);
    if (!run.failure.empty()) {
      run.failedStep = s;
      break;
    }
  }
  run.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - loopStart).count();
  return run;
}

btVector3 centroidOf(const btSoftBody& body) {
  btVector3 centroid(0, 0, 0);
  for (int i = 0; i < body.m_nodes.size(); ++i) centroid += body.m_nodes[i].m_x;
  centroid /= static_cast<btScalar>(body.m_nodes.size());
  return centroid;
}

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse(argc, argv);
  constexpr double radius = 0.5, mass = 1.0, dropHeight = 1.5, gravity = 9.81;

  // The ball, placed so that its lowest vertex is dropHeight above the ground.
  const Mesh mesh = icosphere(radius, 4);
  PlacedBall ball = placeBall(mesh, dropHeight);
  const int nVertices = static_cast<int>(mesh.positions.size());
  const int nTriangles = static_cast<int>(mesh.triangles.size());

  const auto setupStart = std::chrono::steady_clock::now();
  BulletWorld w;
  makeWorld(w, gravity);
  btSoftBody* body = btSoftBodyHelpers::CreateFromTriMesh(w.world->getWorldInfo(), ball.vertices.data(),
                                                          ball.indices.data(), nTriangles,
                                                          /*randomizeConstraints=*/false);
  if (body->m_nodes.size() != nVertices) {
    std::fprintf(stderr, "bullet_ball: expected %d nodes, Bullet made %d\n", nVertices, body->m_nodes.size());
    return 2;
  }
  const LinkCounts links = configureBody(*body, opt, mass);
  w.world->addSoftBody(body);

  const double restVolume = enclosedVolume(*body, mesh.triangles);
  const double setupSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - setupStart).count();
  const long steps = std::lround(opt.duration / opt.dt);
  const btScalar dt = static_cast<btScalar>(opt.dt);
  if (!opt.quiet) {
    std::printf("bullet_ball: Bullet %d, btScalar %zu bytes; icosphere %d vertices, %d triangles, %d edge links + %d "
                "bending links (distance %d)\n",
                btGetVersion(), sizeof(btScalar), nVertices, nTriangles, links.edges, links.bending, opt.bending);
    std::printf("  dt %g s, %ld steps, piterations %d, kLST %g, bending kLST %g, kDP %g, kPR %g, kDF %g, margin %g m, "
                "rest volume %.6f m^3 (sphere %.6f)\n",
                opt.dt, steps, opt.piterations, opt.klst, opt.bendKlst, opt.kdp, opt.kpr, opt.kdf, opt.margin, restVolume,
                4.0 / 3.0 * M_PI * radius * radius * radius);
    std::printf("  centre at y = %.6f m (lowest vertex %.6f m below it); setup %.3f s (not timed below)\n",
                ball.centerY, -ball.minY, setupSeconds);
  }

  const RunRecord run = simulate(*w.world, *body, mesh, restVolume, opt, radius, steps, dt, ball.centerY);
  const double wall = run.wall;
  const long done = run.failedStep > 0 ? run.failedStep : steps;
  const double nsPerVertexStep = 1e9 * wall / (static_cast<double>(done) * nVertices);
  const btVector3 centroid = centroidOf(*body);

  if (!opt.quiet) {
    std::printf("  %ld steps in %.3f s of wall time (%.3f s in stepSimulation), %.0f ns per vertex per step\n", done,
                wall, run.stepSeconds, nsPerVertexStep);
    std::printf("  max edge strain %.4f\n", run.maxStrain);
    std::printf("  first bounce: the centre's highest point after t = 0.7 s %.4f m\n", run.apex);
    std::printf("  volume: min %.4f, max %.4f, end %.4f of rest; lowest vertex %.4f m (at the end %.4f m); end "
                "centroid y %.4f m\n",
                run.minRatio, run.maxRatio, run.ratio, run.lowest, run.endLowest, static_cast<double>(centroid.y()));
    if (run.failedStep > 0) {
      std::printf("  FAILED at step %ld (t = %.4f s): %s\n", run.failedStep,
                  static_cast<double>(run.failedStep) * opt.dt, run.failure.c_str());
    } else {
      std::printf("  ok\n");
    }
  }
  std::printf(
      "result dt=%.9g piterations=%d steps=%ld vertices=%d min_volume=%.6f end_volume=%.6f max_volume=%.6f "
      "wall_s=%.6f step_s=%.6f ns_per_vertex_step=%.1f lowest_y=%.6f end_lowest_y=%.6f end_centroid_y=%.6f links=%d "
      "setup_s=%.3f max_strain=%.6f kpr=%g apex_y=%.6f status=%s\n",
      opt.dt, opt.piterations, done, nVertices, run.minRatio, run.ratio, run.maxRatio, wall, run.stepSeconds,
      nsPerVertexStep, run.lowest, run.endLowest, static_cast<double>(centroid.y()), links.edges + links.bending,
      setupSeconds, run.maxStrain, opt.kpr, run.apex, run.failedStep > 0 ? "fail" : "ok");

  w.world->removeSoftBody(body);
  delete body;
  w.world->removeRigidBody(w.ground.get());
  return run.failedStep > 0 ? 1 : 0;
}
