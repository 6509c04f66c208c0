#include "platform/state_file.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>

namespace floorpose::platform {
namespace {

constexpr char kMagic[8] = {'F', 'P', 'S', 'N', 'A', 'P', '1', '\n'};
constexpr size_t kHeader = sizeof kMagic + 8 + 4;  // magic, payload length, CRC-32
constexpr uint64_t kMaxPayload = 1ull << 30;

void PutLe(uint64_t v, int bytes, std::string* out) {
  for (int i = 0; i < bytes; ++i) out->push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

uint64_t GetLe(const std::string& in, size_t at, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= uint64_t{static_cast<unsigned char>(in[at + i])} << (8 * i);
  return v;
}

uint32_t Crc32(const std::string& data, size_t from) {
  uLong crc = crc32(0L, Z_NULL, 0);
  const auto* p = reinterpret_cast<const Bytef*>(data.data() + from);
  for (size_t left = data.size() - from; left > 0;) {
    const auto n = static_cast<uInt>(std::min<size_t>(left, 1u << 30));
    crc = crc32(crc, p, n);
    p += n;
    left -= n;
  }
  return static_cast<uint32_t>(crc);
}

std::string Errno(const std::string& what) { return what + ": " + std::strerror(errno); }

}  // namespace

bool WriteStateFile(const std::string& path, const google::protobuf::MessageLite& message,
                    std::string* error) {
  std::string bytes(kMagic, sizeof kMagic);
  std::string payload;
  if (!message.SerializeToString(&payload)) {
    *error = "cannot serialise the snapshot";
    return false;
  }
  PutLe(payload.size(), 8, &bytes);
  PutLe(Crc32(payload, 0), 4, &bytes);
  bytes += payload;

  // A new file, never one someone left there (a link would write through it).
  const std::string tmp = path + ".tmp";
  ::unlink(tmp.c_str());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) {
    *error = Errno(tmp);
    return false;
  }
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      *error = Errno("writing " + tmp);
      ::close(fd);
      ::unlink(tmp.c_str());
      return false;
    }
    done += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    *error = Errno("syncing " + tmp);
    ::unlink(tmp.c_str());
    return false;
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    *error = Errno("renaming " + tmp);
    ::unlink(tmp.c_str());
    return false;
  }
  // The rename itself must reach the disk too.
  const std::string dir = std::filesystem::path(path).parent_path().string();
  const int dfd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
  return true;
}

StateRead ReadStateFile(const std::string& path, google::protobuf::MessageLite* message,
                        std::string* error, uint64_t max_bytes) {
  // Not following a link, and not waiting for a FIFO's writer.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    if (errno == ENOENT) return StateRead::kMissing;
    *error = errno == ELOOP ? "a symbolic link, not followed" : Errno("cannot open");
    return StateRead::kBad;
  }
  struct stat st {};
  std::string bytes;
  if (::fstat(fd, &st) != 0) {
    *error = Errno("cannot stat");
  } else if (!S_ISREG(st.st_mode)) {
    *error = S_ISDIR(st.st_mode)    ? "a directory, not a file"
             : S_ISFIFO(st.st_mode) ? "a FIFO, not a file"
                                    : "not a regular file";
  } else if (static_cast<uint64_t>(st.st_size) > max_bytes) {
    *error = std::to_string(st.st_size >> 20) + " MB, over limits.max_snapshot_mb (" +
             std::to_string(max_bytes >> 20) + " MB)";
  } else {
    // At most the size it had: a file that grows while read is cut there (and fails the
    // length check).
    bytes.resize(static_cast<size_t>(st.st_size));
    size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) *error = Errno("cannot read");
      if (n <= 0) break;
      done += static_cast<size_t>(n);
    }
    bytes.resize(done);
  }
  ::close(fd);
  if (!error->empty()) return StateRead::kBad;
  if (bytes.size() < kHeader || bytes.compare(0, sizeof kMagic, kMagic, sizeof kMagic) != 0) {
    *error = "not a floorposed snapshot (no FPSNAP1 header)";
    return StateRead::kBad;
  }
  const uint64_t length = GetLe(bytes, sizeof kMagic, 8);
  if (length > kMaxPayload || length != bytes.size() - kHeader) {
    *error = "truncated or padded: " + std::to_string(bytes.size() - kHeader) +
             " payload bytes where the header says " + std::to_string(length);
    return StateRead::kBad;
  }
  const auto crc = static_cast<uint32_t>(GetLe(bytes, sizeof kMagic + 8, 4));
  if (Crc32(bytes, kHeader) != crc) {
    *error = "checksum mismatch (corrupt)";
    return StateRead::kBad;
  }
  if (!message->ParseFromArray(bytes.data() + kHeader, static_cast<int>(length))) {
    *error = "checksum right but the payload does not parse (another version?)";
    return StateRead::kBad;
  }
  return StateRead::kOk;
}

std::string SetAside(const std::string& path, std::string* error) {
  const std::string aside = path + ".bad-" + std::to_string(std::time(nullptr));
  if (::rename(path.c_str(), aside.c_str()) != 0) {
    *error = Errno("cannot move " + path + " aside");
    return {};
  }
  return aside;
}

std::unique_ptr<StateDirLock> StateDirLock::Take(const std::string& dir, std::string* error) {
  const std::string path = (std::filesystem::path(dir) / "floorposed.lock").string();
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0600);
  if (fd < 0) {
    *error = Errno("cannot open " + path);
    return nullptr;
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const bool held = errno == EWOULDBLOCK;
    *error =
        held ? "state_dir " + dir + " is in use by another floorposed" : Errno("flock " + path);
    char pid[32] = {};
    if (held && ::pread(fd, pid, sizeof pid - 1, 0) > 0)
      *error += " (pid " + std::string(pid, ::strcspn(pid, "\n")) + ")";
    ::close(fd);
    return nullptr;
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, pid.data(), pid.size(), 0) < 0) {
    // The lock holds without the pid in it.
  }
  return std::unique_ptr<StateDirLock>(new StateDirLock(fd));
}

StateDirLock::~StateDirLock() { ::close(fd_); }

std::string SnapshotPath(const std::string& dir, const std::string& device_id) {
  std::string name;
  for (char c : device_id)
    name +=
        std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-' ? c : '_';
  if (name.empty() || name[0] == '.') name = "device" + name;
  return (std::filesystem::path(dir) / (name + ".snapshot")).string();
}

}  // namespace floorpose::platform
