#include "hivecal/wire/byte_reader.hpp"

#include <cstring>

namespace hivecal {

Status MemoryByteReader::read(std::uint8_t* out, std::size_t capacity, std::size_t* count) {
  std::size_t n = bytes_.size() - position_;
  if (n > capacity) n = capacity;
  if (n > 0) std::memcpy(out, bytes_.data() + position_, n);
  position_ += n;
  *count = n;
  return Status::ok;
}

}  // namespace hivecal
