// Reading typed values off a fuzzer's byte string. Past the end every read gives zero bytes, so
// that any input, however short, decodes to something.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace acvo::fuzz {

class Input {
 public:
  Input(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  std::uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }

  template <typename T>
  T raw() {
    unsigned char bytes[sizeof(T)] = {};
    for (auto& b : bytes) b = byte();
    T value;
    std::memcpy(&value, bytes, sizeof(T));
    return value;
  }

  // A value in [lo, hi] from one byte, evenly spread.
  double unit(double lo, double hi) { return lo + (hi - lo) * byte() / 255.0; }

  // The bytes not read yet (empty when all were).
  const std::uint8_t* rest() const { return data_ + pos_; }
  std::size_t restSize() const { return pos_ < size_ ? size_ - pos_ : 0; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

}  // namespace acvo::fuzz
