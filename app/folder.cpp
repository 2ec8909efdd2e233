#include "app/folder.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "app/atomic_file.h"
#include "sim/error.h"

namespace springy {
namespace {

namespace fs = std::filesystem;

// An entry of a folder as its marker lists it.
struct Entry {
  enum class Kind { File, Folder, Other } kind = Kind::Other;
  std::uintmax_t size = 0;  // a file's bytes
  std::uint64_t hash = 0;   // of a file's bytes (contentHash): a change of the same size shows too
  bool operator==(const Entry&) const = default;
};
using Listing = std::map<std::string, Entry>;  // by the path inside the folder

// The line that starts the list in a marker file.
constexpr const char* kListHeader =
    "# What springy wrote here. Anything else (or a file changed since) is kept: springy will not replace\n"
    "# the folder while it holds one.\n";

// Everything under `root` but its marker, symbolic links not followed. Throws springy::Error.
Listing listFolder(const std::string& root, const std::string& marker, const std::string& what) {
  Listing out;
  std::error_code error;
  fs::recursive_directory_iterator it(root, error);
  for (const fs::recursive_directory_iterator end; !error && it != end; it.increment(error)) {
    const std::string inside = it->path().lexically_relative(root).generic_string();
    if (inside == marker) continue;
    struct stat st {};
    Entry& e = out[inside];
    if (::lstat(it->path().c_str(), &st) != 0) continue;  // gone meanwhile: an Other, never springy's
    if (S_ISDIR(st.st_mode)) e.kind = Entry::Kind::Folder;
    if (!S_ISREG(st.st_mode)) continue;
    e.kind = Entry::Kind::File;
    e.size = static_cast<std::uintmax_t>(st.st_size);
    e.hash = contentHash(it->path().string());
  }
  if (error) throw Error(what + ": cannot list the folder " + root + ": " + error.message());
  return out;
}

std::string listingText(const Listing& listing) {
  std::string text = kListHeader;
  for (const auto& [path, e] : listing) {
    if (e.kind == Entry::Kind::Folder) text += "folder " + escapedPath(path) + "\n";
    if (e.kind == Entry::Kind::File) {
      text += "file " + std::to_string(e.size) + " " + std::to_string(e.hash) + " " + escapedPath(path) + "\n";
    }
  }
  return text;
}

// The list in a marker file; nothing for a marker without one (an earlier springy's).
std::optional<Listing> readListing(const std::string& markerPath) {
  std::ifstream in(markerPath, std::ios::binary);
  std::stringstream all;
  all << in.rdbuf();
  const std::string text = all.str();
  const std::size_t at = text.find(kListHeader);
  if (at == std::string::npos) return std::nullopt;
  std::istringstream lines(text.substr(at));
  Listing out;
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string kind;
    words >> kind;
    Entry e;
    if (kind == "folder") {
      e.kind = Entry::Kind::Folder;
    } else if (kind == "file") {
      e.kind = Entry::Kind::File;
      words >> e.size >> e.hash;
    } else {
      continue;
    }
    std::string path;
    std::getline(words >> std::ws, path);
    if (!path.empty()) out[unescapedPath(path)] = e;
  }
  return out;
}

// "a, b, c and 4 more" (at most 10 named).
std::string namesText(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t k = 0; k < names.size() && k < 10; ++k) out += (k ? ", " : "") + names[k];
  if (names.size() > 10) out += " and " + std::to_string(names.size() - 10) + " more";
  return out;
}

// The files and folders of `folder` that its marker does not list (or lists as they were no more).
// Throws springy::Error when its marker lists nothing (an earlier springy's).
std::vector<std::string> foreignEntries(const std::string& folder, const std::string& marker, const std::string& what) {
  const std::optional<Listing> listed = readListing(folder + "/" + marker);
  if (!listed) {
    throw Error(what + ": " + folder + " was written by an earlier springy, whose " + marker +
                " does not list the files it wrote, so a file added to it cannot be told from springy's: move what "
                "you keep out of it and delete the folder, or pick another folder");
  }
  std::vector<std::string> out;
  for (const auto& [path, e] : listFolder(folder, marker, what)) {
    const auto it = listed->find(path);
    if (it == listed->end()) {
      out.push_back(folder + "/" + path);
    } else if (!(it->second == e)) {
      out.push_back(folder + "/" + path + " (changed since springy wrote it)");
    }
  }
  return out;
}

// Removes what `listing` names under `folder`, the marker, then the folder if that left it empty.
// False when something else is left in it.
bool removeListed(const std::string& folder, const Listing& listing, const std::string& marker) {
  std::vector<std::string> folders;
  for (const auto& [path, e] : listing) {
    if (e.kind == Entry::Kind::File) ::unlink((folder + "/" + path).c_str());
    if (e.kind == Entry::Kind::Folder) folders.push_back(path);
  }
  // The deepest first: each one's own folders are gone before it.
  std::sort(folders.begin(), folders.end(), [](const std::string& a, const std::string& b) { return a > b; });
  for (const std::string& path : folders) ::rmdir((folder + "/" + path).c_str());
  ::unlink((folder + "/" + marker).c_str());
  return ::rmdir(folder.c_str()) == 0;
}

}  // namespace

void removeTree(const std::string& path) {
  std::error_code ignored;
  std::filesystem::remove_all(path, ignored);
}

OutputFolder::OutputFolder(std::string target, std::string marker, const std::string& markerText,
                           const std::string& what, const std::vector<std::string>& inputs)
    : target_(std::move(target)), marker_(std::move(marker)), markerText_(markerText), what_(what) {
  if (target_.empty()) throw Error(what_ + ": the folder's name is empty");
  while (target_.size() > 1 && target_.back() == '/') target_.pop_back();
  struct stat st {};
  if (::lstat(target_.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode)) throw Error(what_ + ": " + target_ + " exists and is not a folder");
    // A run that reads a file in the folder would lose it when the folder is replaced.
    std::error_code error;
    const fs::path folder = fs::weakly_canonical(target_, error);
    for (const std::string& input : inputs) {
      std::error_code inputError;
      const fs::path file = fs::weakly_canonical(input, inputError);
      const auto [end, rest] = std::mismatch(folder.begin(), folder.end(), file.begin(), file.end());
      if (!error && !inputError && end == folder.end()) {
        throw Error(what_ + ": " + target_ + " holds " + input +
                    ", which the run reads, and springy replaces the whole folder; pick another folder");
      }
    }
    refuseForeign();
  }
  const fs::path t(target_);
  const fs::path parent = t.has_parent_path() ? t.parent_path() : fs::path(".");
  std::string temporary = (parent / ("." + t.filename().string() + ".tmp-XXXXXX")).string();
  if (!::mkdtemp(temporary.data())) {
    throw Error(what_ + ": cannot create a folder in " + parent.string() + ": " + errorText(errno));
  }
  temporary_ = temporary;
  registered_ = registerTemporary(temporary_, true);
  try {
    writeFileAtomically(temporary_ + "/" + marker_, markerText_);
  } catch (...) {
    removeTree(temporary_);
    forgetTemporary(registered_);
    throw;
  }
}

OutputFolder::~OutputFolder() {
  if (!temporary_.empty()) removeTree(temporary_);
  forgetTemporary(registered_);
}

void OutputFolder::refuseForeign() const {
  if (::access((target_ + "/" + marker_).c_str(), F_OK) != 0) {
    std::error_code error;
    if (std::filesystem::is_empty(target_, error) && !error) return;  // an empty folder is taken
    throw Error(what_ + ": " + target_ + " exists, is not empty and was not written by springy (it holds no " +
                marker_ + "); pick another folder or empty it");
  }
  const std::vector<std::string> foreign = foreignEntries(target_, marker_, what_);
  if (foreign.empty()) return;
  throw Error(what_ + ": " + target_ + " holds " + std::to_string(foreign.size()) +
              (foreign.size() == 1 ? " file" : " files") + " that springy did not write: " + namesText(foreign) +
              "; springy replaces the whole folder: move them out of it, or pick another folder (" + target_ +
              " left as it was)");
}

void OutputFolder::fail(const std::string& what, int error) const {
  throw Error(what_ + ": " + target_ + ": " + what + ": " + errorText(error) + " (" + target_ + " left as it was)");
}

void OutputFolder::commit() {
  // The marker lists what was written, for the next command that replaces the folder.
  writeFileAtomically(temporary_ + "/" + marker_, markerText_ + listingText(listFolder(temporary_, marker_, what_)));
  // What was written reaches the disk before the folder gets its name.
  const int dir = ::open(temporary_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir < 0 || ::syncfs(dir) != 0) fail("writing failed", errno);
  ::close(dir);
  std::string old;
  std::optional<Listing> oldListing;
  struct stat st {};
  if (::lstat(target_.c_str(), &st) == 0) {
    refuseForeign();  // again: a file may have been added to it during the run
    oldListing = readListing(target_ + "/" + marker_);
    old = temporary_ + ".old";
    if (std::rename(target_.c_str(), old.c_str()) != 0) fail("cannot move the earlier folder aside", errno);
  }
  if (std::rename(temporary_.c_str(), target_.c_str()) != 0) {
    const int error = errno;
    if (!old.empty()) std::rename(old.c_str(), target_.c_str());
    fail("cannot rename the finished folder into place", error);
  }
  temporary_.clear();
  forgetTemporary(registered_);
  registered_ = -1;
  // Only what springy listed goes: a file added in the instant since the check above is kept.
  if (!old.empty() && !removeListed(old, oldListing.value_or(Listing{}), marker_)) {
    std::cerr << "springy: " << what_ << ": kept " << old << ": files were added to " << target_
              << " while it was replaced\n";
  }
}

}  // namespace springy
