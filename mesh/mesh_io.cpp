#include "mesh/mesh_io.h"

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <new>
#include <numeric>
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

#include "sim/error.h"
#include "sim/limits.h"

namespace springy {

namespace {

// Area below kZeroAreaFactor * (bounding-box diagonal)^2 counts as zero: relative, so the test
// does not depend on the mesh's units, and tiny enough that only truly collapsed (collinear or
// coincident) corners trip it, not small but well-formed triangles of a fine scan.
constexpr double kZeroAreaFactor = 1e-12;

// Same idea for loadClosedMesh's enclosed-volume test, relative to diagonal^3.
constexpr double kZeroVolumeFactor = 1e-12;

// An edge this many times longer than the median edge makes a mesh unusable as a body: welding
// and the zero-area test are relative to the bounding box, which the stray vertex sets.
constexpr double kStrayEdgeRatio = 1e6;

// Built by appending: `"(" + std::to_string(...)` trips GCC 12's false -Wrestrict (PR 105329).
std::string listText(std::initializer_list<uint32_t> values) {
  std::string text = "(";
  for (uint32_t v : values) {
    if (text.size() > 1) text += ", ";
    text += std::to_string(v);
  }
  text += ")";
  return text;
}

std::string edgeText(uint32_t a, uint32_t b) { return listText({a, b}); }
std::string triangleText(const Triangle& t) { return listText({t[0], t[1], t[2]}); }

double boundsDiagonal(const std::vector<Vec3>& positions) {
  if (positions.empty()) return 0.0;
  return length(boundsOf(positions).size());
}

// Union-find whose root is always the smallest index of its set, so the result does not depend
// on the order in which unions happen.
class MinUnionFind {
 public:
  explicit MinUnionFind(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), uint32_t{0});
  }
  uint32_t find(uint32_t i) {
    while (parent_[i] != i) {
      parent_[i] = parent_[parent_[i]];  // path halving
      i = parent_[i];
    }
    return i;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (a < b) {
      parent_[b] = a;
    } else {
      parent_[a] = b;
    }
  }

 private:
  std::vector<uint32_t> parent_;
};

// Appends one assimp mesh with `transform` applied in double precision. A mirroring transform
// (negative determinant) reverses the winding, so its triangles get two corners swapped to keep
// the file's intended orientation.
void appendMesh(const aiMesh& mesh, const aiMatrix4x4& t, TriMesh& out) {
  // Nodes may instance one mesh many times: the total is what memory follows.
  if (out.positions.size() + mesh.mNumVertices > kMaxMeshVertices ||
      out.triangles.size() + mesh.mNumFaces > kMaxMeshTriangles) {
    throw Error("its meshes and their instances add up to more than " + std::to_string(kMaxMeshVertices) +
                " vertices or " + std::to_string(kMaxMeshTriangles) + " triangles (the limits)");
  }
  const bool mirrored = t.Determinant() < 0.0f;
  const auto base = static_cast<uint32_t>(out.positions.size());
  for (unsigned int v = 0; v < mesh.mNumVertices; ++v) {
    const double x = mesh.mVertices[v].x;
    const double y = mesh.mVertices[v].y;
    const double z = mesh.mVertices[v].z;
    out.positions.push_back({t.a1 * x + t.a2 * y + t.a3 * z + t.a4,
                             t.b1 * x + t.b2 * y + t.b3 * z + t.b4,
                             t.c1 * x + t.c2 * y + t.c3 * z + t.c4});
  }
  for (unsigned int f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices != 3) continue;  // points and lines are not surface
    Triangle tri{base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]};
    if (mirrored) std::swap(tri[1], tri[2]);
    out.triangles.push_back(tri);
  }
}

// Appends every mesh instance below `node`, each with its accumulated node transform.
void collectNode(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parentTransform,
                 std::vector<bool>& meshSeen, TriMesh& out, int depth = 0) {
  constexpr int kMaxDepth = 1000;  // a deeper node tree is corrupt, and would exhaust the stack
  if (depth > kMaxDepth) throw Error("its node tree is more than " + std::to_string(kMaxDepth) + " levels deep");
  const aiMatrix4x4 transform = parentTransform * node.mTransformation;
  for (unsigned int m = 0; m < node.mNumMeshes; ++m) {
    const unsigned int meshIndex = node.mMeshes[m];
    if (meshIndex >= scene.mNumMeshes) continue;
    meshSeen[meshIndex] = true;
    appendMesh(*scene.mMeshes[meshIndex], transform, out);
  }
  for (unsigned int c = 0; c < node.mNumChildren; ++c) {
    collectNode(scene, *node.mChildren[c], transform, meshSeen, out, depth + 1);
  }
}

// Signed volume about the bounding-box centre: the same quantity as signedVolume() for a closed
// mesh, with less cancellation when the mesh sits far from the origin.
double centredVolume(const TriMesh& mesh) {
  const Vec3 c = boundsOf(mesh.positions).center();
  double sixVolume = 0.0;
  for (const Triangle& t : mesh.triangles) {
    sixVolume +=
        dot(mesh.positions[t[0]] - c, cross(mesh.positions[t[1]] - c, mesh.positions[t[2]] - c));
  }
  return sixVolume / 6.0;
}

// One triangle side, stored with its undirected key (lo, hi) plus the direction it was walked.
struct HalfEdge {
  uint32_t lo, hi;
  uint32_t from, to;
  uint32_t triangle;
};

// assimp takes the PLY magic in any case ("pLy": found by the fuzzer, then a header without its
// end hung the reader); so does checkPlyCounts.
bool isPlyMagic(const std::string& first) {
  return first.size() >= 3 && std::tolower(static_cast<unsigned char>(first[0])) == 'p' &&
         std::tolower(static_cast<unsigned char>(first[1])) == 'l' &&
         std::tolower(static_cast<unsigned char>(first[2])) == 'y';
}

// The bytes one binary PLY scalar of this type takes.
std::uint64_t plyTypeBytes(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "double" || type == "float64") return 8;
  return 4;
}

// What a PLY header declares, line by line: its format, and per element the count and the least
// bytes one takes (binary: the sizes of its scalar properties and list counts; ASCII: a digit
// and a separator per property), summed into the least bytes its body needs.
class PlyHeader {
 public:
  explicit PlyHeader(const std::string& path) : path_(path) {}

  // Reads one header line after the magic; true at end_header, when every count is summed.
  bool read(const std::string& line) {
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "format") {
      std::string format;
      words >> format;
      ascii_ = format == "ascii";
    } else if (keyword == "element") {
      closeElement();
      words >> element_ >> count_;
      if (!words) throw Error(path_ + ": the PLY header's line '" + line + "' is not 'element NAME COUNT'");
      elementBytes_ = 0;
    } else if (keyword == "property" && !element_.empty()) {
      std::string type;
      words >> type;
      if (type == "list") {
        std::string countType;
        words >> countType;
        elementBytes_ += ascii_ ? 2 : plyTypeBytes(countType);
      } else {
        elementBytes_ += ascii_ ? 2 : plyTypeBytes(type);
      }
    } else if (keyword == "end_header") {
      closeElement();
      return true;
    }
    return false;
  }

  bool ascii() const { return ascii_; }
  std::uintmax_t needed() const { return needed_; }
  std::uint64_t elements() const { return elements_; }

 private:
  // Adds the element declared last to the sums; a count past the mesh limits is refused.
  void closeElement() {
    if (element_.empty()) return;
    const std::uint64_t limit = element_ == "face" ? kMaxMeshTriangles : kMaxMeshVertices;
    if (count_ > limit) {
      throw Error(path_ + ": the PLY header declares " + std::to_string(count_) + " " + element_ +
                  " elements, more than the limit of " + std::to_string(limit));
    }
    needed_ += count_ * std::max<std::uint64_t>(elementBytes_, 1);
    elements_ += count_;
  }

  const std::string& path_;
  bool ascii_ = true;
  std::uintmax_t needed_ = 0;   // bytes the declared elements need at the least
  std::uint64_t elements_ = 0;  // all elements declared: ASCII has one line each
  std::string element_;         // the element declared last, its count and the least bytes of one
  std::uint64_t count_ = 0, elementBytes_ = 0;
};

// Step of checkPlyCounts, after the header: the body (`body` bytes, `in` at its start) must be
// large enough for what the header declares, and an ASCII body have a line per element.
void checkPlyBody(const std::string& path, const PlyHeader& header, std::uintmax_t body, std::ifstream& in) {
  // ASCII: the last value of the file may lack its separator.
  if (header.needed() > body + 1) {
    throw Error(path + ": the PLY header declares elements that need at least " + std::to_string(header.needed()) +
                " bytes, but the file has only " + std::to_string(body) +
                " after its header: the file is truncated or its header is wrong");
  }
  if (!header.ascii()) return;
  // assimp's ASCII reader fills elements missing at a cut with zeros; count the lines.
  std::uint64_t lines = 0;
  std::string line;
  while (lines < header.elements() && std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") != std::string::npos) ++lines;
  }
  if (lines < header.elements()) {
    throw Error(path + ": the PLY header declares " + std::to_string(header.elements()) +
                " elements (one line each), but " + "the file has only " + std::to_string(lines) +
                " lines after its header: the file is truncated");
  }
}

// A PLY header declares its element counts up front, and assimp allocates for them before it
// reads the body: a 200-byte file claiming 2e9 vertices took all memory. Each element needs at
// least a known number of bytes, so the counts the file can hold follow from its size. Returns
// nothing to say for a file that is not PLY or whose header assimp will reject anyway.
void checkPlyCounts(const std::string& path, std::uintmax_t fileSize) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!std::getline(in, line) || !isPlyMagic(line)) return;
  PlyHeader header(path);
  std::uintmax_t headerBytes = line.size() + 1;
  for (int headerLines = 0; headerLines < 10000 && std::getline(in, line); ++headerLines) {
    headerBytes += line.size() + 1;
    if (header.read(line)) {
      checkPlyBody(path, header, fileSize > headerBytes ? fileSize - headerBytes : 0, in);
      return;
    }
  }
  // assimp's PLY reader loops forever on a header without its end (found by the fuzzer).
  throw Error(path + ": the PLY header has no end_header line: the file is truncated or not PLY");
}

// Assimp post-processes what its importers produced without checking it first: a truncated file
// left faces with indices past the vertex array, and triangulating them crashed (SIGSEGV, or an
// assertion in TriangulateProcess). So the file is read with validation only, every face checked
// here, and triangulation applied afterwards.
void checkFaces(const aiScene& scene, const std::string& path) {
  for (unsigned int m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[m];
    if (mesh.mNumVertices > kMaxMeshVertices || mesh.mNumFaces > kMaxMeshTriangles) {
      throw Error(path + ": mesh " + std::to_string(m) + " has " + std::to_string(mesh.mNumVertices) +
                  " vertices and " + std::to_string(mesh.mNumFaces) + " faces, more than the limits of " +
                  std::to_string(kMaxMeshVertices) + " and " + std::to_string(kMaxMeshTriangles));
    }
    if (mesh.mNumFaces > 0 && (mesh.mFaces == nullptr || mesh.mVertices == nullptr)) {
      throw Error(path + ": mesh " + std::to_string(m) + " has faces but no vertex data: the file is corrupt");
    }
    for (unsigned int f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices == 0 || face.mIndices == nullptr) {
        throw Error(path + ": face " + std::to_string(f) + " has no corners: the file is truncated or corrupt");
      }
      for (unsigned int k = 0; k < face.mNumIndices; ++k) {
        if (face.mIndices[k] >= mesh.mNumVertices) {
          throw Error(path + ": face " + std::to_string(f) + " refers to vertex " + std::to_string(face.mIndices[k]) +
                      ", but the file has only " + std::to_string(mesh.mNumVertices) +
                      " vertices: the file is truncated or corrupt");
        }
      }
    }
  }
}

}  // namespace

namespace {

// assimp catches what its importers throw and keeps the message; running out of memory is
// thrown on as std::bad_alloc, for readInChild to say what limit the file ran into.
[[noreturn]] void importFailed(const std::string& path, const Assimp::Importer& importer) {
  const std::string why = importer.GetErrorString();
  if (why == std::bad_alloc().what()) throw std::bad_alloc();
  throw Error(path + ": cannot read mesh file: " + why);
}

// The reading itself, with assimp, in the calling process.
TriMesh readWithAssimp(const std::string& path) {
  Assimp::Importer importer;
  // Validation, then (after our own checks) triangulation only: welding is done by
  // weldVertices, deterministically and with our tolerance.
  const aiScene* scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
  if (scene == nullptr) importFailed(path, importer);
  checkFaces(*scene, path);
  scene = importer.ApplyPostProcessing(aiProcess_Triangulate);
  if (scene == nullptr) importFailed(path, importer);

  TriMesh out;
  std::vector<bool> meshSeen(scene->mNumMeshes, false);
  try {
    if (scene->mRootNode != nullptr) {
      collectNode(*scene, *scene->mRootNode, aiMatrix4x4(), meshSeen, out);
    }
    // Meshes no node refers to are unusual but still part of the file; take them untransformed.
    for (unsigned int m = 0; m < scene->mNumMeshes; ++m) {
      if (!meshSeen[m]) appendMesh(*scene->mMeshes[m], aiMatrix4x4(), out);
    }
  } catch (const Error& e) {
    throw Error(path + ": " + e.what());
  }

  if (out.triangles.empty()) {
    throw Error(path + ": the file holds no triangles");
  }
  for (std::size_t i = 0; i < out.positions.size(); ++i) {
    if (!isFinite(out.positions[i])) {
      throw Error(path + ": vertex " + std::to_string(i) + " has a non-finite coordinate");
    }
  }
  return out;
}

bool writeAll(int fd, const void* data, std::size_t size) {
  const auto* bytes = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, bytes, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    bytes += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

bool readAll(int fd, void* data, std::size_t size) {
  auto* bytes = static_cast<char*>(data);
  while (size > 0) {
    const ssize_t n = ::read(fd, bytes, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    bytes += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

// The child's exit status when it passed its memory limit in a sanitizer build (below).
constexpr int kChildOutOfMemory = 4;

std::string outOfMemoryText(const std::string& path, std::uint64_t limit, std::uintmax_t fileBytes) {
  return path + ": cannot read mesh file: the reader (assimp) needed more than " + std::to_string(limit >> 20) +
         " MiB for a file of " + std::to_string(fileBytes) +
         " bytes (springy's limit for a file of that size: README, Limits): the file is corrupt, or too large to read";
}

#if defined(__SANITIZE_ADDRESS__) || defined(SPRINGY_FUZZING)
}  // namespace
// The sanitizer runtime's allocation hooks (declared in LLVM's sanitizer/allocator_interface.h,
// which GCC does not install).
extern "C" {
std::size_t __sanitizer_get_allocated_size(const volatile void* p);
int __sanitizer_install_malloc_and_free_hooks(void (*mallocHook)(const volatile void*, std::size_t),
                                              void (*freeHook)(const volatile void*));
}
namespace {
// A sanitizer reserves terabytes of address space, so no address-space limit fits its build: the
// child counts its heap instead (bytes allocated since the fork less bytes freed) and ends with
// kChildOutOfMemory past the limit. The child has one thread (fork copies only the caller).
std::int64_t childHeap = 0, childHeapLimit = 0;
void countAllocation(const volatile void*, std::size_t size) {
  childHeap += static_cast<std::int64_t>(size);
  if (childHeap > childHeapLimit) ::_exit(kChildOutOfMemory);
}
void countRelease(const volatile void* p) {
  if (p != nullptr) childHeap -= static_cast<std::int64_t>(__sanitizer_get_allocated_size(p));
}
void limitChildMemory(std::uint64_t limit) {
  childHeapLimit = static_cast<std::int64_t>(limit);
  __sanitizer_install_malloc_and_free_hooks(countAllocation, countRelease);
}
#else
// The address space the child has from its parent (program, libraries, heap) and `limit` more.
void limitChildMemory(std::uint64_t limit) {
  unsigned long long pages = 0;
  if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%llu", &pages) != 1) pages = 0;
    std::fclose(f);
  }
  const rlim_t bytes = static_cast<rlim_t>(pages * static_cast<unsigned long long>(::sysconf(_SC_PAGESIZE)) + limit);
  const rlimit memory{bytes, bytes};
  ::setrlimit(RLIMIT_AS, &memory);
}
#endif

// The child's side: reads with assimp and sends the mesh (status 0) or the error (status 1).
[[noreturn]] void readInChild(const std::string& path, std::uintmax_t fileBytes, int fd) {
  ::alarm(kMeshReadSeconds);  // a hang ends as SIGALRM, which the parent reports
  limitChildMemory(meshReadBytes(fileBytes));
  bool ok = true;
  try {
    const TriMesh mesh = readWithAssimp(path);
    const uint8_t status = 0;
    const uint64_t counts[2] = {mesh.positions.size(), mesh.triangles.size()};
    ok = writeAll(fd, &status, 1) && writeAll(fd, counts, sizeof counts) &&
         writeAll(fd, mesh.positions.data(), mesh.positions.size() * sizeof(Vec3)) &&
         writeAll(fd, mesh.triangles.data(), mesh.triangles.size() * sizeof(Triangle));
  } catch (const std::exception& e) {
    const uint8_t status = 1;
    const std::string message = dynamic_cast<const Error*>(&e) ? e.what()
                                : dynamic_cast<const std::bad_alloc*>(&e)
                                    ? outOfMemoryText(path, meshReadBytes(fileBytes), fileBytes)
                                    : path + ": cannot read mesh file: " + e.what();
    const uint64_t size = message.size();
    ok = writeAll(fd, &status, 1) && writeAll(fd, &size, sizeof size) && writeAll(fd, message.data(), message.size());
  }
  ::_exit(ok ? 0 : 3);  // no atexit handlers or destructors of the parent's objects
}

}  // namespace

TriMesh readMeshFile(const std::string& path) {
  const std::uintmax_t fileSize = checkInputFile(path, kMaxMeshFileBytes, "mesh file");
  checkPlyCounts(path, fileSize);
  // assimp is a large parser of many formats, and a corrupt file can crash it, hang it or make
  // it allocate without bound (the fuzzer found segmentation faults in its importers). It runs
  // in a child process with a time and memory limit; whatever happens there, the parent gets a
  // mesh or an error naming the file.
  int fds[2];
  if (::pipe(fds) != 0) throw Error(path + ": cannot read mesh file: pipe: " + std::strerror(errno));
  const pid_t child = ::fork();
  if (child < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    throw Error(path + ": cannot read mesh file: fork: " + std::strerror(errno));
  }
  if (child == 0) {
    ::close(fds[0]);
    readInChild(path, fileSize, fds[1]);
  }
  ::close(fds[1]);
  uint8_t status = 2;
  TriMesh out;
  std::string message;
  if (readAll(fds[0], &status, 1)) {
    uint64_t counts[2] = {0, 0};
    if (status == 0 && readAll(fds[0], counts, sizeof counts) && counts[0] <= kMaxMeshVertices &&
        counts[1] <= kMaxMeshTriangles) {
      out.positions.resize(counts[0]);
      out.triangles.resize(counts[1]);
      if (!readAll(fds[0], out.positions.data(), counts[0] * sizeof(Vec3)) ||
          !readAll(fds[0], out.triangles.data(), counts[1] * sizeof(Triangle))) {
        status = 2;
      }
    } else if (status == 1 && readAll(fds[0], counts, sizeof(uint64_t)) && counts[0] < (1u << 20)) {
      message.resize(counts[0]);
      if (!readAll(fds[0], message.data(), message.size())) status = 2;
    } else {
      status = 2;
    }
  }
  ::close(fds[0]);
  int wait = 0;
  while (::waitpid(child, &wait, 0) < 0 && errno == EINTR) {
  }
  if (status == 1) throw Error(message);
  if (status == 0 && WIFEXITED(wait) && WEXITSTATUS(wait) == 0) return out;
  if (WIFEXITED(wait) && WEXITSTATUS(wait) == kChildOutOfMemory) {
    throw Error(outOfMemoryText(path, meshReadBytes(fileSize), fileSize));
  }
  if (WIFSIGNALED(wait) && WTERMSIG(wait) == SIGALRM) {
    throw Error(path + ": cannot read mesh file: reading took longer than " + std::to_string(kMeshReadSeconds) +
                " s (the file is corrupt, or too large)");
  }
  throw Error(path + ": cannot read mesh file: the reader (assimp) failed on it (" +
              (WIFSIGNALED(wait) ? std::string("signal ") + std::to_string(WTERMSIG(wait))
                                 : "exit status " + std::to_string(WEXITSTATUS(wait))) +
              ", or out of memory): the file is corrupt or not a mesh assimp reads");
}

namespace {

// Step of weldVertices: unites every two finite vertices within `tolerance` [mesh units]. A
// uniform grid with cell size = tolerance: any two vertices within tolerance lie in the same or
// adjacent cells. The cells are a sorted array (not a hash map) so that nothing depends on
// iteration order; the distance test decides, the cells only prune.
void uniteNearVertices(const TriMesh& mesh, double tolerance, MinUnionFind& sets) {
  const std::size_t n = mesh.positions.size();
  using Cell = std::array<int64_t, 3>;
  constexpr double kCellLimit = 4.0e18;  // keeps the cast in int64 range; clamped cells merge
  auto cellOf = [&](const Vec3& p) {
    Cell c{};
    for (int k = 0; k < 3; ++k) {
      const double q = std::clamp(std::floor(p[k] / tolerance), -kCellLimit, kCellLimit);
      c[static_cast<std::size_t>(k)] = static_cast<int64_t>(q);
    }
    return c;
  };
  std::vector<std::pair<Cell, uint32_t>> sorted;
  sorted.reserve(n);
  for (uint32_t i = 0; i < n; ++i) {
    // Non-finite vertices stay on their own; validation reports them.
    if (isFinite(mesh.positions[i])) sorted.emplace_back(cellOf(mesh.positions[i]), i);
  }
  std::sort(sorted.begin(), sorted.end());
  const double tol2 = tolerance * tolerance;
  for (const auto& [cell, i] : sorted) {
    for (int64_t dx = -1; dx <= 1; ++dx) {
      for (int64_t dy = -1; dy <= 1; ++dy) {
        for (int64_t dz = -1; dz <= 1; ++dz) {
          const Cell key{cell[0] + dx, cell[1] + dy, cell[2] + dz};
          auto it = std::lower_bound(sorted.begin(), sorted.end(), key,
                                     [](const auto& e, const Cell& k) { return e.first < k; });
          for (; it != sorted.end() && it->first == key; ++it) {
            const uint32_t j = it->second;
            if (j > i && lengthSquared(mesh.positions[j] - mesh.positions[i]) <= tol2) {
              sets.unite(i, j);
            }
          }
        }
      }
    }
  }
}

// Step of weldVertices at zero tolerance: unites exactly equal positions only.
void uniteEqualVertices(const TriMesh& mesh, MinUnionFind& sets) {
  const std::size_t n = mesh.positions.size();
  std::vector<uint32_t> order;
  order.reserve(n);
  for (uint32_t i = 0; i < n; ++i) {
    if (isFinite(mesh.positions[i])) order.push_back(i);
  }
  auto key = [&](uint32_t i) {
    const Vec3& p = mesh.positions[i];
    return std::tuple(p.x, p.y, p.z, i);
  };
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
  for (std::size_t k = 1; k < order.size(); ++k) {
    if (mesh.positions[order[k]] == mesh.positions[order[k - 1]])
      sets.unite(order[k - 1], order[k]);
  }
}

// Step of weldVertices: the mesh on the sets' representatives. Corners are remapped to them (the
// smallest original index) and collapsed triangles dropped; the vertices left are renumbered in
// increasing original index, so an already welded mesh comes back unchanged. A merged vertex
// keeps its representative's position exactly rather than an average.
TriMesh weldedMesh(const TriMesh& mesh, MinUnionFind& sets) {
  const std::size_t n = mesh.positions.size();
  std::vector<Triangle> triangles;
  triangles.reserve(mesh.triangles.size());
  std::vector<bool> used(n, false);
  for (const Triangle& t : mesh.triangles) {
    const Triangle r{sets.find(t[0]), sets.find(t[1]), sets.find(t[2])};
    if (r[0] == r[1] || r[1] == r[2] || r[0] == r[2]) continue;
    triangles.push_back(r);
    for (uint32_t v : r) used[v] = true;
  }
  TriMesh out;
  std::vector<uint32_t> newIndex(n, 0);
  for (uint32_t i = 0; i < n; ++i) {
    if (!used[i]) continue;
    newIndex[i] = static_cast<uint32_t>(out.positions.size());
    out.positions.push_back(mesh.positions[i]);
  }
  out.triangles.reserve(triangles.size());
  for (const Triangle& t : triangles) {
    out.triangles.push_back({newIndex[t[0]], newIndex[t[1]], newIndex[t[2]]});
  }
  return out;
}

// Step of findManifoldProblem: the cheap per-element checks, first so that later checks can index
// and measure safely: finite coordinates, corners that exist, no zero-area triangle, no unused
// vertex.
std::optional<std::string> elementProblem(const TriMesh& mesh) {
  const std::vector<Vec3>& pos = mesh.positions;
  const std::vector<Triangle>& tris = mesh.triangles;
  const auto vertexCount = static_cast<uint32_t>(pos.size());
  for (uint32_t i = 0; i < vertexCount; ++i) {
    if (!isFinite(pos[i])) return "vertex " + std::to_string(i) + " has a non-finite coordinate";
  }
  for (std::size_t t = 0; t < tris.size(); ++t) {
    for (uint32_t v : tris[t]) {
      if (v >= vertexCount) {
        return "triangle " + std::to_string(t) + " " + triangleText(tris[t]) +
               " refers to vertex " + std::to_string(v) + ", but the mesh has only " +
               std::to_string(vertexCount) + " vertices";
      }
    }
  }
  const double diagonal = boundsDiagonal(pos);
  const double minArea = kZeroAreaFactor * diagonal * diagonal;
  for (std::size_t t = 0; t < tris.size(); ++t) {
    const Triangle& tri = tris[t];
    const double area = 0.5 * length(cross(pos[tri[1]] - pos[tri[0]], pos[tri[2]] - pos[tri[0]]));
    // `<=` so that repeated corners are caught even when every vertex coincides (diagonal 0).
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] || area <= minArea) {
      return "triangle " + std::to_string(t) + " " + triangleText(tri) + " has zero area";
    }
  }
  std::vector<bool> used(vertexCount, false);
  for (const Triangle& t : tris) {
    for (uint32_t v : t) used[v] = true;
  }
  for (uint32_t i = 0; i < vertexCount; ++i) {
    if (!used[i]) return "vertex " + std::to_string(i) + " is not used by any triangle";
  }
  return std::nullopt;
}

// The uses of one undirected edge: halfEdges[begin, end).
struct EdgeGroup {
  std::size_t begin, end;
};

// All half-edges sorted by undirected key, so each edge's uses are adjacent, and their groups.
std::vector<HalfEdge> sortedHalfEdges(const std::vector<Triangle>& tris, std::vector<EdgeGroup>& groups) {
  std::vector<HalfEdge> halfEdges;
  halfEdges.reserve(3 * tris.size());
  for (std::size_t t = 0; t < tris.size(); ++t) {
    for (std::size_t k = 0; k < 3; ++k) {
      const uint32_t a = tris[t][k];
      const uint32_t b = tris[t][(k + 1) % 3];
      halfEdges.push_back({std::min(a, b), std::max(a, b), a, b, static_cast<uint32_t>(t)});
    }
  }
  std::sort(halfEdges.begin(), halfEdges.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return std::tie(x.lo, x.hi, x.triangle, x.from) < std::tie(y.lo, y.hi, y.triangle, y.from);
  });
  for (std::size_t i = 0; i < halfEdges.size();) {
    std::size_t j = i + 1;
    while (j < halfEdges.size() && halfEdges[j].lo == halfEdges[i].lo &&
           halfEdges[j].hi == halfEdges[i].hi) {
      ++j;
    }
    groups.push_back({i, j});
    i = j;
  }
  return halfEdges;
}

// Step of findManifoldProblem: every edge in at most two triangles, in two unless the surface is
// open, and walked in opposite directions by them. Each category is checked over all edges before
// the next, so the most severe problem is reported.
std::optional<std::string> edgeProblem(const std::vector<Triangle>& tris, Surface surface) {
  std::vector<EdgeGroup> groups;
  const std::vector<HalfEdge> halfEdges = sortedHalfEdges(tris, groups);
  for (const EdgeGroup& g : groups) {
    if (g.end - g.begin > 2) {
      const HalfEdge& e = halfEdges[g.begin];
      return "edge " + edgeText(e.lo, e.hi) + " is shared by " + std::to_string(g.end - g.begin) +
             " triangles: non-manifold edge";
    }
  }
  for (const EdgeGroup& g : groups) {
    if (g.end - g.begin == 1 && surface == Surface::Closed) {
      const HalfEdge& e = halfEdges[g.begin];
      return "edge " + edgeText(e.lo, e.hi) + " belongs to 1 triangle: the mesh has a hole";
    }
  }
  for (const EdgeGroup& g : groups) {
    if (g.end - g.begin == 1) continue;  // a border edge (Surface::Open)
    const HalfEdge& e0 = halfEdges[g.begin];
    const HalfEdge& e1 = halfEdges[g.begin + 1];
    if (e0.from == e1.from) {
      return "edge " + edgeText(e0.from, e0.to) + " is traversed twice in the same direction " +
             "(triangles " + std::to_string(e0.triangle) + " and " + std::to_string(e1.triangle) +
             "): flipped face";
    }
  }
  return std::nullopt;
}

// A link step (v, a, b): triangle (v, a, b) steps from a to b around its corner v.
using LinkStep = std::array<uint32_t, 3>;

// Marks the link steps of one vertex (steps[begin, end), sorted by a) on the path or cycle from
// step i. With consistent orientation every a has exactly one step out, so a cycle's walk comes
// back to i.
void walkLink(const std::vector<LinkStep>& steps, std::size_t begin, std::size_t end, std::size_t i,
              std::vector<bool>& visited) {
  const auto first = steps.begin() + static_cast<std::ptrdiff_t>(begin);
  const auto last = steps.begin() + static_cast<std::ptrdiff_t>(end);
  while (i < end && !visited[i]) {
    visited[i] = true;
    const LinkStep probe{steps[i][0], steps[i][2], 0};
    const auto next = std::lower_bound(first, last, probe);
    if (next == last || (*next)[1] != steps[i][2]) break;
    i = static_cast<std::size_t>(next - steps.begin());
  }
}

// The separate fans of triangles around one vertex: the paths and cycles its link steps
// steps[begin, end) form. `ends`: scratch.
std::size_t countFans(const std::vector<LinkStep>& steps, std::size_t begin, std::size_t end, Surface surface,
                      std::vector<bool>& visited, std::vector<uint32_t>& ends) {
  std::size_t fans = 0;
  if (surface == Surface::Open) {
    // Paths first, each from its first step (one whose a no step ends at), so that a path is
    // walked whole; what is left is cycles. On a closed surface there are no paths.
    ends.clear();
    for (std::size_t i = begin; i < end; ++i) ends.push_back(steps[i][2]);
    std::sort(ends.begin(), ends.end());
    for (std::size_t i = begin; i < end; ++i) {
      if (visited[i] || std::binary_search(ends.begin(), ends.end(), steps[i][1])) continue;
      ++fans;
      walkLink(steps, begin, end, i, visited);
    }
  }
  for (std::size_t i = begin; i < end; ++i) {
    if (visited[i]) continue;
    ++fans;
    walkLink(steps, begin, end, i, visited);
  }
  return fans;
}

// Step of findManifoldProblem: every edge is now shared by two opposite triangles (or, open, is a
// border edge), yet a vertex can still join two or more separate fans (two cones touching at
// their tips). Around vertex v, each triangle (v, a, b) contributes the link step a -> b; a
// manifold vertex's steps form exactly one cycle, or on an open surface's border one path. (Each
// a starts at most one step and each b ends at most one, by the checks before, so the steps form
// paths and cycles.)
std::optional<std::string> fanProblem(const std::vector<Triangle>& tris, Surface surface) {
  // Link steps grouped by vertex, sorted by `a` so the successor of a is found by binary search.
  std::vector<LinkStep> steps;
  steps.reserve(3 * tris.size());
  for (const Triangle& t : tris) {
    for (std::size_t k = 0; k < 3; ++k) steps.push_back({t[k], t[(k + 1) % 3], t[(k + 2) % 3]});
  }
  std::sort(steps.begin(), steps.end());
  std::vector<bool> visited(steps.size(), false);
  std::vector<uint32_t> ends;  // Surface::Open: the b of one vertex's steps, sorted
  for (std::size_t begin = 0; begin < steps.size();) {
    std::size_t end = begin + 1;
    while (end < steps.size() && steps[end][0] == steps[begin][0]) ++end;
    const std::size_t fans = countFans(steps, begin, end, surface, visited, ends);
    if (fans > 1) {
      return "vertex " + std::to_string(steps[begin][0]) + " joins " + std::to_string(fans) +
             " separate fans of triangles: non-manifold vertex";
    }
    begin = end;
  }
  return std::nullopt;
}

// Step of findManifoldProblem: connectivity: one piece, or the body would be several bodies.
std::optional<std::string> pieceProblem(const TriMesh& mesh) {
  const auto vertexCount = static_cast<uint32_t>(mesh.positions.size());
  MinUnionFind pieces(vertexCount);
  for (const Triangle& t : mesh.triangles) {
    pieces.unite(t[0], t[1]);
    pieces.unite(t[1], t[2]);
  }
  std::size_t pieceCount = 0;
  uint32_t firstOther = 0;
  for (uint32_t i = 0; i < vertexCount; ++i) {
    if (pieces.find(i) != i) continue;
    if (pieceCount == 1) firstOther = i;
    ++pieceCount;
  }
  if (pieceCount > 1) {
    return "the mesh has " + std::to_string(pieceCount) + " separate pieces (vertex 0 and vertex " +
           std::to_string(firstOther) + " are not connected)";
  }
  return std::nullopt;
}

}  // namespace

TriMesh weldVertices(const TriMesh& mesh, double tolerance) {
  MinUnionFind sets(mesh.positions.size());
  if (tolerance > 0.0) {
    uniteNearVertices(mesh, tolerance, sets);
  } else {
    uniteEqualVertices(mesh, sets);
  }
  return weldedMesh(mesh, sets);
}

std::optional<std::string> findManifoldProblem(const TriMesh& mesh, Surface surface) {
  if (mesh.triangles.empty()) return "the mesh has no triangles";
  if (auto problem = elementProblem(mesh)) return problem;
  if (auto problem = edgeProblem(mesh.triangles, surface)) return problem;
  if (auto problem = fanProblem(mesh.triangles, surface)) return problem;
  return pieceProblem(mesh);
}

std::optional<std::string> findStrayVertex(const TriMesh& mesh) {
  std::vector<double> lengths;
  lengths.reserve(3 * mesh.triangles.size());
  for (const Triangle& t : mesh.triangles) {
    for (std::size_t k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a < mesh.positions.size() && b < mesh.positions.size()) {
        lengths.push_back(length(mesh.positions[b] - mesh.positions[a]));
      }
    }
  }
  if (lengths.empty()) return std::nullopt;
  const auto middle = lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2);
  std::nth_element(lengths.begin(), middle, lengths.end());
  const double median = *middle;
  const double longest = *std::max_element(lengths.begin(), lengths.end());
  if (!(median > 0.0) || longest <= kStrayEdgeRatio * median) return std::nullopt;
  // The stray vertex is the end of a longest edge farther from the coordinate-wise median point.
  Vec3 centre;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> c;
    c.reserve(mesh.positions.size());
    for (const Vec3& p : mesh.positions) c.push_back(p[axis]);
    const auto mid = c.begin() + static_cast<std::ptrdiff_t>(c.size() / 2);
    std::nth_element(c.begin(), mid, c.end());
    centre[axis] = *mid;
  }
  uint32_t worst = 0;
  for (uint32_t i = 1; i < mesh.positions.size(); ++i) {
    if (lengthSquared(mesh.positions[i] - centre) > lengthSquared(mesh.positions[worst] - centre)) worst = i;
  }
  const Vec3& p = mesh.positions[worst];
  std::ostringstream text;
  // By position: the reader's vertex numbers are not the file's (OBJ corners are split per face).
  text << "the vertex at (" << p.x << ", " << p.y << ", " << p.z << ") is a stray: an edge of "
       << longest << " where the median edge is " << median << " (over " << kStrayEdgeRatio
       << " times longer); remove it from the file";
  return text.str();
}

bool orientOutward(TriMesh& mesh) {
  if (centredVolume(mesh) >= 0.0) return false;
  for (Triangle& t : mesh.triangles) std::swap(t[1], t[2]);
  return true;
}

TriMesh readWeldedMesh(const std::string& path, double relativeWeldTolerance) {
  const TriMesh raw = readMeshFile(path);
  if (auto stray = findStrayVertex(raw)) throw Error(path + ": " + *stray);
  return weldVertices(raw, relativeWeldTolerance * boundsDiagonal(raw.positions));
}

void finishClosedMesh(TriMesh& mesh, const std::string& path) {
  if (auto problem = findManifoldProblem(mesh)) {
    throw Error(path + ": " + *problem);
  }
  orientOutward(mesh);
  // A closed manifold can still enclose nothing (two coincident sheets); a body needs volume.
  const double diagonal = boundsDiagonal(mesh.positions);
  if (centredVolume(mesh) <= kZeroVolumeFactor * diagonal * diagonal * diagonal) {
    throw Error(path + ": the mesh encloses no volume");
  }
}

void finishClothMesh(const TriMesh& mesh, const std::string& path) {
  if (auto problem = findManifoldProblem(mesh, Surface::Open)) throw Error(path + ": " + *problem);
}

TriMesh loadClosedMesh(const std::string& path, double relativeWeldTolerance) {
  TriMesh mesh = readWeldedMesh(path, relativeWeldTolerance);
  finishClosedMesh(mesh, path);
  return mesh;
}

namespace {

// One meshoptimizer pass to about targetVertices; the result may be non-manifold.
TriMesh simplifyOnce(const TriMesh& mesh, std::size_t targetVertices) {
  const std::size_t vertexCount = mesh.positions.size();
  const std::size_t triangleCount = mesh.triangles.size();
  // Each edge collapse on a closed manifold removes one vertex and two triangles, whatever the
  // genus, so F_target = F - 2 (V - V_target) (= 2 V_target - 4 for a sphere). A tetrahedron is
  // the smallest closed mesh.
  const std::size_t removedTriangles = 2 * (vertexCount - targetVertices);
  const std::size_t targetTriangles =
      removedTriangles + 4 <= triangleCount ? triangleCount - removedTriangles : 4;

  // meshoptimizer works on floats and a flat index buffer; the output indices refer to the
  // original vertices, whose double positions are kept.
  std::vector<float> floats;
  floats.reserve(3 * vertexCount);
  for (const Vec3& p : mesh.positions) {
    floats.push_back(static_cast<float>(p.x));
    floats.push_back(static_cast<float>(p.y));
    floats.push_back(static_cast<float>(p.z));
  }
  std::vector<unsigned int> indices;
  indices.reserve(3 * triangleCount);
  for (const Triangle& t : mesh.triangles) indices.insert(indices.end(), t.begin(), t.end());

  std::vector<unsigned int> simplified(indices.size());  // worst case is the input size
  // target_error is relative to the mesh extents; 1 (the whole extent) means "no error limit":
  // the caller asked for a vertex count, and meshoptimizer still refuses topology changes.
  constexpr float kNoErrorLimit = 1.0f;
  const std::size_t indexCount = meshopt_simplify(simplified.data(), indices.data(), indices.size(),
                                                  floats.data(), vertexCount, 3 * sizeof(float),
                                                  3 * targetTriangles, kNoErrorLimit, 0, nullptr);
  simplified.resize(indexCount);

  // Compact: keep the surviving vertices in their original order.
  std::vector<uint32_t> newIndex(vertexCount, UINT32_MAX);
  for (unsigned int v : simplified) newIndex[v] = 0;
  TriMesh out;
  for (std::size_t i = 0; i < vertexCount; ++i) {
    if (newIndex[i] == UINT32_MAX) continue;
    newIndex[i] = static_cast<uint32_t>(out.positions.size());
    out.positions.push_back(mesh.positions[i]);
  }
  out.triangles.reserve(indexCount / 3);
  for (std::size_t k = 0; k + 2 < indexCount; k += 3) {
    out.triangles.push_back(
        {newIndex[simplified[k]], newIndex[simplified[k + 1]], newIndex[simplified[k + 2]]});
  }

  return out;
}

}  // namespace

TriMesh simplifyMesh(const TriMesh& mesh, std::size_t targetVertices) {
  if (auto problem = findManifoldProblem(mesh)) {
    throw Error("simplifyMesh: the input is not a closed manifold: " + *problem);
  }
  if (targetVertices >= mesh.positions.size()) return mesh;
  // meshoptimizer's edge collapses occasionally pinch two sheets together (a non-manifold edge)
  // at one particular target; a neighbouring target avoids it. Try a few, in a fixed order, so
  // the result stays deterministic.
  std::string firstProblem;
  const std::size_t tries = std::max<std::size_t>(8, targetVertices / 50);
  for (std::size_t k = 0; k < tries && targetVertices + k < mesh.positions.size(); ++k) {
    TriMesh out = simplifyOnce(mesh, targetVertices + k);
    const std::optional<std::string> problem = findManifoldProblem(out);
    if (!problem) return out;
    if (firstProblem.empty()) firstProblem = *problem;
  }
  throw Error("simplifyMesh: simplifying to " + std::to_string(targetVertices) + " vertices (and up to " +
              std::to_string(targetVertices + tries - 1) + ") broke the mesh: " + firstProblem);
}

}  // namespace springy
