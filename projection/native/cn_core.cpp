// Errors, argument checks, handle registries and package path resolution.
#include "cn_internal.hpp"

#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <sched.h>
#include <sys/stat.h>
#include <time.h>

namespace cn {

static thread_local std::string t_error;
static thread_local int t_code = 0;

std::string fmt(const char *f, ...) {
  char buf[1024];
  va_list ap;
  va_start(ap, f);
  vsnprintf(buf, sizeof buf, f, ap);
  va_end(ap);
  return buf;
}

std::string num(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return fmt("%g", v);
}

void fail(int code, const char *f, ...) {
  char buf[1024];
  va_list ap;
  va_start(ap, f);
  vsnprintf(buf, sizeof buf, f, ap);
  va_end(ap);
  throw Error(code, buf);
}

int set_error(int code, const std::string &msg) {
  t_error = msg;
  t_code = code;
  return code;
}

void clear_error() {
  t_error.clear();
  t_code = 0;
}

int guard_exception() {
  try {
    throw;
  } catch (const Error &e) {
    return set_error(e.code, e.msg);
  } catch (const std::bad_alloc &) {
    return set_error(CN_E_INTERNAL, "out of memory");
  } catch (const std::exception &e) {
    return set_error(CN_E_INTERNAL, std::string("internal error: ") + e.what());
  } catch (...) {
    return set_error(CN_E_INTERNAL, "internal error of unknown type");
  }
}

void check_ptr(const void *p, const char *what) {
  if (!p) fail(CN_E_ARG, "%s is a null pointer", what);
}

void check_output(int cap, const void *p, const char *what) {
  if (cap < 0) fail(CN_E_ARG, "capacity %d, expected >= 0", cap);
  if (cap > 0) check_ptr(p, what);
}

double check_finite(double v, const char *what) {
  if (!std::isfinite(v)) fail(CN_E_ARG, "%s is %s, expected a finite number", what, num(v).c_str());
  return v;
}

double check_positive(double v, const char *what) {
  if (!std::isfinite(v) || v <= 0) fail(CN_E_ARG, "%s is %s, expected a finite number > 0", what, num(v).c_str());
  return v;
}

double check_nonneg(double v, const char *what) {
  if (!std::isfinite(v) || v < 0) fail(CN_E_ARG, "%s is %s, expected a finite number >= 0", what, num(v).c_str());
  return v;
}

btTransform read_pose(const double *p, const char *what) {
  if (!p) fail(CN_E_ARG, "%s is a null pointer", what);
  bool finite = true;
  for (int i = 0; i < 7; ++i) finite &= std::isfinite(p[i]);
  if (!finite)
    for (int i = 0; i < 7; ++i)
      if (!std::isfinite(p[i]))
        fail(CN_E_ARG, "%s has %s in component %d (%s)", what,
             std::isnan(p[i]) ? "NaN" : "an infinity", i,
             (const char *[]){"x", "y", "z", "qx", "qy", "qz", "qw"}[i]);
  btTransform t;
  if (!pose_into(p, t))
    fail(CN_E_ARG, "%s has a zero quaternion (%g %g %g %g)", what, p[3], p[4], p[5], p[6]);
  return t;
}

bool fp_tame(const double *p, int n) {
#if defined(__x86_64__) || defined(__i386__)
  const unsigned quiet = 0x0800u | 0x0100u | 0x1000u;  // underflow, denormal, precision masked
  if ((_mm_getcsr() & quiet) != quiet || !p) return false;
  for (int i = 0; i < n; ++i) {  // on the bits: no floating point operation may trap here
    uint64_t b;
    std::memcpy(&b, p + i, 8);
    int e = (int)((b >> 52) & 0x7ff);  // biased binary exponent: 1023 +- 330 is about 1e+-100
    if ((b << 1) != 0 && (e < 1023 - 330 || e > 1023 + 330)) return false;  // NaN, inf too
  }
  return true;
#else
  (void)p, (void)n;
  return false;
#endif
}

void write_pose(const btTransform &t, double *o) {
  const btVector3 &v = t.getOrigin();
  btQuaternion q = t.getRotation();
  o[0] = v.x(); o[1] = v.y(); o[2] = v.z();
  o[3] = q.x(); o[4] = q.y(); o[5] = q.z(); o[6] = q.w();
}

std::string check_str(const char *s, const char *what) {
  if (!s) fail(CN_E_ARG, "%s is a null pointer, expected a string", what);
  return std::string(s);
}

std::atomic<int> g_api_lock{0};
thread_local int t_api_depth = 0;

void api_lock_wait() {
  for (int i = 0;; ++i) {
    if (g_api_lock.load(std::memory_order_relaxed) == 0 &&
        !g_api_lock.exchange(1, std::memory_order_acquire))
      return;
    if (i < 64) {
#if defined(__x86_64__) || defined(__i386__)
      _mm_pause();
#endif
    } else if (i < 256) {
      sched_yield();
    } else {
      struct timespec ts = {0, 20000};  // 20 us
      nanosleep(&ts, nullptr);
    }
  }
}

// ---- world registry: handle = generation << 14 | slot -----------------------------------------
static const int kSlots = 1 << 14;
static World *g_worlds[kSlots];
static int g_gen[kSlots];
static std::mutex g_world_mutex;
static std::vector<int> g_free;
static int g_next_slot = 0;
static int g_live = 0;

int world_register(World *w) {
  std::lock_guard<std::mutex> lock(g_world_mutex);
  int slot;
  if (!g_free.empty()) {
    slot = g_free.back();
    g_free.pop_back();
  } else if (g_next_slot < kSlots) {
    slot = g_next_slot++;
  } else {
    fail(CN_E_STATE, "too many live worlds (%d)", kSlots);
  }
  g_gen[slot] = (g_gen[slot] % 65535) + 1;
  g_worlds[slot] = w;
  ++g_live;
  return (g_gen[slot] << 14) | slot;
}

static bool world_ok(int h) {
  if (h < 0) return false;
  int slot = h & (kSlots - 1);
  return g_worlds[slot] && g_gen[slot] == (h >> 14);
}

World &world(int h) {
  if (!world_ok(h)) fail(CN_E_HANDLE, "world handle %d is not a live world", h);
  return *g_worlds[h & (kSlots - 1)];
}

void world_unregister(int h) {
  std::lock_guard<std::mutex> lock(g_world_mutex);
  int slot = h & (kSlots - 1);
  g_worlds[slot] = nullptr;
  g_free.push_back(slot);
  --g_live;
}

// ---- package paths ------------------------------------------------------------------------------
static std::mutex g_path_mutex;
static std::map<std::string, std::string> g_packages;
static std::vector<std::string> g_search_dirs;

static bool is_file(const std::string &p) {
  struct stat st;
  return stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}
static bool is_dir(const std::string &p) {
  struct stat st;
  return stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

static std::vector<std::string> split_path(const char *s) {
  std::vector<std::string> out;
  if (!s) return out;
  std::string cur;
  for (const char *c = s;; ++c) {
    if (*c == ':' || *c == 0) {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
      if (!*c) break;
    } else {
      cur += *c;
    }
  }
  return out;
}

static std::string find_package(const std::string &name) {
  {
    std::lock_guard<std::mutex> lock(g_path_mutex);
    auto it = g_packages.find(name);
    if (it != g_packages.end()) return it->second;
    for (auto &d : g_search_dirs)
      if (is_dir(d + "/" + name)) return d + "/" + name;
  }
  for (auto &d : split_path(getenv("ROS_PACKAGE_PATH"))) {
    if (is_dir(d + "/" + name)) return d + "/" + name;
    size_t slash = d.find_last_of('/');
    if (d.substr(slash == std::string::npos ? 0 : slash + 1) == name) return d;
  }
  if (is_dir("/usr/share/" + name)) return "/usr/share/" + name;
  fail(CN_E_NAME,
       "unknown package '%s' (not registered with cn_add_package_path, not in a search "
       "directory nor in ROS_PACKAGE_PATH)",
       name.c_str());
}

std::string resolve_path(const std::string &uri, const std::string &base) {
  std::string p;
  if (uri.rfind("package://", 0) == 0) {
    std::string rest = uri.substr(10);
    size_t slash = rest.find('/');
    if (slash == std::string::npos || slash == 0)
      fail(CN_E_ARG, "malformed package URI '%s', expected package://NAME/path", uri.c_str());
    p = find_package(rest.substr(0, slash)) + rest.substr(slash);
  } else if (uri.rfind("file://", 0) == 0) {
    p = uri.substr(7);
  } else if (!uri.empty() && uri[0] != '/' && !base.empty()) {
    p = base + "/" + uri;
  } else {
    p = uri;
  }
  if (uri.empty()) fail(CN_E_FILE, "empty file name");
  if (!is_file(p) && !p.empty() && p[0] != '/') {
    std::lock_guard<std::mutex> lock(g_path_mutex);
    for (auto &d : g_search_dirs)
      if (is_file(d + "/" + p)) return d + "/" + p;
  }
  if (!is_file(p)) {
    if (p == uri) fail(CN_E_FILE, "file '%s' does not exist", uri.c_str());
    fail(CN_E_FILE, "file '%s' (from '%s') does not exist", p.c_str(), uri.c_str());
  }
  return p;
}

}  // namespace cn

using namespace cn;

extern "C" {

const char *cn_last_error(void) { return t_error.c_str(); }
int cn_last_error_code(void) { return t_code; }
int cn_version(void) { return 10100; }

int cn_add_package_path(const char *name, const char *dir) {
  return guard([&] {
    std::string n = check_str(name, "package name"), d = check_str(dir, "package directory");
    if (n.empty() || n.find('/') != std::string::npos)
      fail(CN_E_ARG, "package name '%s' must be non-empty and contain no '/'", n.c_str());
    if (!is_dir(d)) fail(CN_E_FILE, "package directory '%s' does not exist", d.c_str());
    std::lock_guard<std::mutex> lock(g_path_mutex);
    g_packages[n] = d;
    return 0;
  });
}

int cn_add_search_dir(const char *dir) {
  return guard([&] {
    std::string d = check_str(dir, "search directory");
    if (!is_dir(d)) fail(CN_E_FILE, "search directory '%s' does not exist", d.c_str());
    std::lock_guard<std::mutex> lock(g_path_mutex);
    for (auto &e : g_search_dirs)
      if (e == d) return 0;
    g_search_dirs.push_back(d);
    return 0;
  });
}

int cn_clear_search_paths(void) {
  return guard([&] {
    std::lock_guard<std::mutex> lock(g_path_mutex);
    g_packages.clear();
    g_search_dirs.clear();
    return 0;
  });
}

int cn_resolve_path(const char *uri, const char *base_dir, char *out, int cap) {
  return guard([&] {
    std::string u = check_str(uri, "path");
    check_ptr(out, "output buffer");
    if (cap <= 0) fail(CN_E_ARG, "buffer capacity %d, expected > 0", cap);
    std::string p = resolve_path(u, base_dir ? base_dir : "");
    if ((int)p.size() + 1 > cap)
      fail(CN_E_ARG, "resolved path has %d characters, buffer holds %d", (int)p.size(), cap - 1);
    memcpy(out, p.c_str(), p.size() + 1);
    return (int)p.size();
  });
}

int cn_world_alive(int w) {
  cn::ApiLock lock;
  return world_ok(w) ? 1 : 0;
}
int cn_world_count(void) {
  cn::ApiLock lock;
  return g_live;
}

}  // extern "C"
