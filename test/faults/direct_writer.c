// The negative control of the write-time fault tests: copies FROM to TO by writing TO in
// place (open with O_TRUNC, one write, close), the way a writer that is not atomic does.
//   direct_writer FROM TO
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

int main(int argc, char** argv) {
  if (argc != 3) {
    fprintf(stderr, "usage: direct_writer FROM TO\n");
    return 2;
  }
  FILE* in = fopen(argv[1], "rb");
  if (!in) return perror(argv[1]), 1;
  static char buf[1 << 20];
  const size_t n = fread(buf, 1, sizeof(buf), in);
  fclose(in);
  const int fd = open(argv[2], O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) return perror(argv[2]), 1;
  if (write(fd, buf, n) != (ssize_t)n) return perror(argv[2]), 1;
  return close(fd) == 0 ? 0 : 1;
}
