// LD_PRELOAD shim for the write-time fault tests (test/scripts/test_write_faults.sh): SIGKILLs
// the process at the Nth file-output event on a path that contains a pattern.
//   KILL_PATTERN  substring of the paths watched (required)
//   KILL_AT       N >= 1: die at the Nth event; 0: only count
//   KILL_COUNT    file that receives the number of events at exit (counting runs)
// Events: open/creat/fopen of a watched path, each write/fwrite on it (the Nth one writes half
// its bytes, flushes them, then dies: a kill in the middle of a write), fflush, fsync,
// fdatasync, syncfs, close/fclose, and rename/renameat/renameat2 with a watched source or
// target (two events: just before and just after the rename).
#define _GNU_SOURCE
#include <dlfcn.h>
#include <fcntl.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/syscall.h>
#include <unistd.h>

#define MAX_FD 65536
static unsigned char watched_fd[MAX_FD];
static long events;

static const char* pattern(void) {
  const char* p = getenv("KILL_PATTERN");
  return p && *p ? p : NULL;
}
static int watched(const char* path) {
  const char* p = pattern();
  return p && path && strstr(path, p) != NULL;
}
static int watchedFd(int fd) { return fd >= 0 && fd < MAX_FD && watched_fd[fd]; }
static void die(void) { syscall(SYS_kill, getpid(), SIGKILL); }
// Counts one event; true when it is the one to die at.
static int event(void) {
  const long n = __atomic_add_fetch(&events, 1, __ATOMIC_SEQ_CST);
  const char* at = getenv("KILL_AT");
  return at && atol(at) > 0 && n == atol(at);
}
#define REAL(ret, name, ...)              \
  static ret (*real_##name)(__VA_ARGS__); \
  if (!real_##name) real_##name = (ret(*)(__VA_ARGS__))dlsym(RTLD_NEXT, #name)

__attribute__((destructor)) static void report(void) {
  const char* f = getenv("KILL_COUNT");
  if (!f || !pattern()) return;
  char buf[32];
  const int len = snprintf(buf, sizeof(buf), "%ld\n", events);
  const int fd = (int)syscall(SYS_openat, AT_FDCWD, f, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) return;
  if (syscall(SYS_write, fd, buf, (size_t)len) < 0) {
  }
  syscall(SYS_close, fd);
}

static int opened(const char* path, int fd) {
  if (fd >= 0 && fd < MAX_FD) watched_fd[fd] = (unsigned char)watched(path);
  return fd;
}
static void beforeOpen(const char* path) {
  if (watched(path) && event()) die();
}

int open(const char* path, int flags, ...) {
  REAL(int, open, const char*, int, ...);
  va_list ap;
  va_start(ap, flags);
  const mode_t mode = (mode_t)va_arg(ap, int);
  va_end(ap);
  beforeOpen(path);
  return opened(path, real_open(path, flags, mode));
}
int open64(const char* path, int flags, ...) {
  REAL(int, open64, const char*, int, ...);
  va_list ap;
  va_start(ap, flags);
  const mode_t mode = (mode_t)va_arg(ap, int);
  va_end(ap);
  beforeOpen(path);
  return opened(path, real_open64(path, flags, mode));
}
int openat(int dir, const char* path, int flags, ...) {
  REAL(int, openat, int, const char*, int, ...);
  va_list ap;
  va_start(ap, flags);
  const mode_t mode = (mode_t)va_arg(ap, int);
  va_end(ap);
  beforeOpen(path);
  return opened(path, real_openat(dir, path, flags, mode));
}
int creat(const char* path, mode_t mode) {
  REAL(int, creat, const char*, mode_t);
  beforeOpen(path);
  return opened(path, real_creat(path, mode));
}
FILE* fopen(const char* path, const char* mode) {
  REAL(FILE*, fopen, const char*, const char*);
  beforeOpen(path);
  FILE* f = real_fopen(path, mode);
  if (f) opened(path, fileno(f));
  return f;
}
FILE* fopen64(const char* path, const char* mode) {
  REAL(FILE*, fopen64, const char*, const char*);
  beforeOpen(path);
  FILE* f = real_fopen64(path, mode);
  if (f) opened(path, fileno(f));
  return f;
}

ssize_t write(int fd, const void* buf, size_t n) {
  REAL(ssize_t, write, int, const void*, size_t);
  if (watchedFd(fd) && event()) {
    if (n > 1) real_write(fd, buf, n / 2);
    die();
  }
  return real_write(fd, buf, n);
}
size_t fwrite(const void* buf, size_t size, size_t n, FILE* f) {
  REAL(size_t, fwrite, const void*, size_t, size_t, FILE*);
  REAL(int, fflush, FILE*);
  if (watchedFd(fileno(f)) && event()) {
    const size_t bytes = size * n;
    if (bytes > 1) real_fwrite(buf, 1, bytes / 2, f);
    real_fflush(f);
    die();
  }
  return real_fwrite(buf, size, n, f);
}
int fflush(FILE* f) {
  REAL(int, fflush, FILE*);
  if (f && watchedFd(fileno(f)) && event()) die();
  return real_fflush(f);
}
int fsync(int fd) {
  REAL(int, fsync, int);
  if (watchedFd(fd) && event()) die();
  return real_fsync(fd);
}
int fdatasync(int fd) {
  REAL(int, fdatasync, int);
  if (watchedFd(fd) && event()) die();
  return real_fdatasync(fd);
}
int syncfs(int fd) {
  REAL(int, syncfs, int);
  if (watchedFd(fd) && event()) die();
  return real_syncfs(fd);
}
int close(int fd) {
  REAL(int, close, int);
  if (watchedFd(fd)) {
    watched_fd[fd] = 0;
    if (event()) die();
  }
  return real_close(fd);
}
int fclose(FILE* f) {
  REAL(int, fclose, FILE*);
  if (f) {
    const int fd = fileno(f);
    if (watchedFd(fd)) {
      watched_fd[fd] = 0;
      if (event()) die();
    }
  }
  return real_fclose(f);
}

static int renameEvents(const char* from, const char* to, int rc) {
  if ((watched(from) || watched(to)) && event()) die();
  return rc;
}
int rename(const char* from, const char* to) {
  REAL(int, rename, const char*, const char*);
  renameEvents(from, to, 0);
  return renameEvents(from, to, real_rename(from, to));
}
int renameat(int fd1, const char* from, int fd2, const char* to) {
  REAL(int, renameat, int, const char*, int, const char*);
  renameEvents(from, to, 0);
  return renameEvents(from, to, real_renameat(fd1, from, fd2, to));
}
int renameat2(int fd1, const char* from, int fd2, const char* to, unsigned int flags) {
  REAL(int, renameat2, int, const char*, int, const char*, unsigned int);
  renameEvents(from, to, 0);
  return renameEvents(from, to, real_renameat2(fd1, from, fd2, to, flags));
}
