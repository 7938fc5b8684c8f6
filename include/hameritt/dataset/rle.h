#pragma once
// COCO run-length encoding of binary masks, exactly as pycocotools writes it (maskApi.c):
// runs over the pixels in column-major order (x * height + y), the first run counting zeros
// (it may be 0), and the compressed "counts" string of rleToString (LEB128-like 5-bit groups,
// each count after the second stored as the difference to the count two places before).

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace hameritt::dataset {

// A mask that cannot be encoded or a "counts" string that cannot be decoded.
class RleError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Pixel extent of the pixels of one instance (inclusive bounds) and their number.
struct MaskExtent {
  int x_min = 0, y_min = 0, x_max = -1, y_max = -1;
  std::uint32_t pixels = 0;
  bool empty() const { return pixels == 0; }
};

// The column-major runs of the mask (instances == id) of a width x height instance image
// (row-major, 16 bit), scanning only the columns of `extent` (the mask's extent, or an empty
// extent for an empty mask). Sums to width * height.
std::vector<std::uint32_t> encodeInstanceMask(const std::uint16_t* instances, int width, int height,
                                              std::uint16_t id, const MaskExtent& extent);

// pycocotools' rleToString: the compressed "counts" string of the runs.
std::string countsToString(const std::vector<std::uint32_t>& counts);

// pycocotools' rleFrString: the runs of a compressed "counts" string; throws RleError for a
// character outside '0'..'o' or a string that ends inside a count.
std::vector<std::uint32_t> countsFromString(const std::string& s);

// The row-major 0/1 mask of width x height pixels that the runs describe; throws RleError when
// the runs do not sum to width * height.
std::vector<std::uint8_t> decodeRuns(const std::vector<std::uint32_t>& counts, int width,
                                     int height);

}  // namespace hameritt::dataset
