#include "recording/recording_file.hpp"

#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace haptic::recording {
namespace {

constexpr std::size_t kFlushBytes = 64 * 1024;  // records gathered before a compression step
constexpr int kLevel = 3;                      // zstd's default: fast, and samples compress well
constexpr std::size_t kBlockHeader = 3;        // a zstd block's header (RFC 8878)

void append_varint(std::string& out, std::uint64_t value) {
  while (value >= 0x80) {
    out.push_back(static_cast<char>((value & 0x7f) | 0x80));
    value >>= 7;
  }
  out.push_back(static_cast<char>(value));
}

}  // namespace

RecordingWriter::RecordingWriter(const std::string& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "wb");
  if (file_ == nullptr) {
    throw std::runtime_error("recording '" + path + "': cannot create it: " + std::strerror(errno));
  }
  context_ = ZSTD_createCCtx();
  ZSTD_CCtx_setParameter(context_, ZSTD_c_compressionLevel, kLevel);
  ZSTD_CCtx_setParameter(context_, ZSTD_c_checksumFlag, 1);  // a damaged file is caught on reading
}

RecordingWriter::~RecordingWriter() {
  close();
}

bool RecordingWriter::write(const v1::Record& record) {
  ++offered_;
  if (!error_.empty() || file_ == nullptr) return false;
  append_varint(pending_, record.ByteSizeLong());
  record.AppendToString(&pending_);
  ++pending_records_;
  if (pending_.size() < kFlushBytes) return true;
  return compress(Directive::kFlush);
}

bool RecordingWriter::flush() {
  if (!error_.empty() || file_ == nullptr) return false;
  return compress(Directive::kFlush);
}

bool RecordingWriter::compress(Directive directive) {
  // Whole blocks of whole records, handed to the file at once: a writer killed between two
  // leaves a file that ends right after a record.
  ZSTD_inBuffer in{pending_.data(), pending_.size(), 0};
  const ZSTD_EndDirective mode = directive == Directive::kEnd ? ZSTD_e_end : ZSTD_e_flush;
  out_.resize(ZSTD_CStreamOutSize());
  for (;;) {
    ZSTD_outBuffer out{out_.data(), out_.size(), 0};
    const std::size_t remaining = ZSTD_compressStream2(context_, &out, &in, mode);
    if (ZSTD_isError(remaining)) {
      error_ = std::string("zstd: ") + ZSTD_getErrorName(remaining);
      break;
    }
    if (out.pos > 0 && std::fwrite(out_.data(), 1, out.pos, file_) != out.pos) {
      const int why = errno;
      error_ = "writing '" + path_ + "': " + std::strerror(why);
      break;
    }
    if (remaining == 0) break;
  }
  pending_.clear();
  if (error_.empty() && std::fflush(file_) != 0) {
    const int why = errno;
    error_ = "writing '" + path_ + "': " + std::strerror(why);
  }
  if (error_.empty()) in_file_ += pending_records_;  // else they count as not written
  pending_records_ = 0;
  return error_.empty();
}

bool RecordingWriter::close() {
  if (file_ == nullptr) return error_.empty();
  if (error_.empty()) compress(Directive::kEnd);  // after a failed write, the stream is broken
  if (std::fclose(file_) != 0 && error_.empty()) error_ = "closing '" + path_ + "': " + std::strerror(errno);
  file_ = nullptr;
  ZSTD_freeCCtx(context_);
  context_ = nullptr;
  return error_.empty();
}

RecordingReader::RecordingReader(const std::string& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "rb");
  if (file_ == nullptr) {
    throw std::runtime_error("recording '" + path + "': cannot open it: " + std::strerror(errno));
  }
  context_ = ZSTD_createDCtx();
}

RecordingReader::~RecordingReader() {
  if (file_ != nullptr) std::fclose(file_);
  ZSTD_freeDCtx(context_);
}

bool RecordingReader::fill(std::size_t bytes) {
  if (size_ - read_ >= bytes) return true;
  // Room after what is unread for the bytes wanted and a block's output: what was consumed is
  // dropped (the few unread bytes move to the front); the buffer grows only for a record larger
  // than any before. Nothing is allocated or zero-filled otherwise.
  const std::size_t block = ZSTD_DStreamOutSize();
  const std::size_t room = bytes + block;
  if (capacity_ - read_ < room) {
    const std::size_t unread = size_ - read_;
    if (capacity_ < room) {
      const std::size_t capacity = std::max(room, 2 * block);
      std::unique_ptr<char[]> grown(new char[capacity]);  // not zero-filled: written before read
      if (unread > 0) std::memcpy(grown.get(), buffer_.get() + read_, unread);
      buffer_ = std::move(grown);
      capacity_ = capacity;
    } else if (unread > 0) {
      std::memmove(buffer_.get(), buffer_.get() + read_, unread);
    }
    base_ += read_;
    size_ = unread;
    read_ = 0;
  }
  if (!in_) {
    in_capacity_ = ZSTD_DStreamInSize();
    in_.reset(new char[in_capacity_]);
  }
  while (size_ - read_ < bytes) {
    if (in_used_ == in_size_) {
      if (file_done_) return false;
      in_size_ = std::fread(in_.get(), 1, in_capacity_, file_);
      in_used_ = 0;
      file_bytes_ += in_size_;
      if (in_size_ == 0) {
        file_done_ = true;
        // Mid-frame (or nothing at all): cut short, not ended. next() says where.
        cut_short_ = !frame_done_ || file_bytes_ == 0;
        return false;
      }
    }
    ZSTD_inBuffer in{in_.get(), in_size_, in_used_};
    // At least a block's room: the loop keeps size_ - read_ < bytes, and capacity_ - read_ >= room.
    ZSTD_outBuffer out{buffer_.get() + size_, capacity_ - size_, 0};
    const std::size_t result = ZSTD_decompressStream(context_, &out, &in);
    if (ZSTD_isError(result)) {
      error_ = "recording '" + path_ + "': not a readable recording (zstd: " +
               ZSTD_getErrorName(result) + ")";
      file_done_ = true;
      return false;
    }
    frame_done_ = result == 0;
    hint_ = result;
    in_used_ = in.pos;
    size_ += out.pos;
  }
  return true;
}

bool RecordingReader::next(v1::Record& record) {
  const std::uint64_t start = base_ + read_;  // where this record begins (fill() may move it)
  // Why there is no whole record here: the file cut short (where, in the stream and in the
  // record), or a frame that ended inside a record (damage). `length`: the record's, when known.
  const auto stopped = [&](std::uint64_t length) {
    if (!error_.empty()) return false;  // zstd's complaint
    const std::uint64_t there = base_ + size_ - start;
    if (!cut_short_) {
      if (there > 0) error_ = "recording '" + path_ + "': the last record is cut short";
      return false;  // else a clean end
    }
    if (file_bytes_ == 0) {
      error_ = "recording '" + path_ + "': the file is empty (cut short: its writer was killed?)";
      return false;
    }
    // zstd's hint is the input it wants next: at a block's end, the next block's header alone;
    // inside a block, the rest of it too (the hint is that and the header after it).
    error_ = "recording '" + path_ + "': the file ends in the middle";
    error_ += hint_ == kBlockHeader
                  ? " of its compressed stream, at the end of a block"
                  : " of a compressed block (" +
                        std::to_string(hint_ > kBlockHeader ? hint_ - kBlockHeader : hint_) +
                        " more bytes were due; what it holds is lost)";
    if (there == 0) {
      error_ += ", after a whole record";
    } else {
      error_ += ", inside a record (" + std::to_string(there) +
                (length > 0 ? " of its " + std::to_string(length) : std::string()) + " bytes are there)";
    }
    error_ += ": cut short (its writer killed?)";
    return false;
  };
  // The varint length: up to 10 bytes.
  std::uint64_t length = 0;
  for (int shift = 0;; shift += 7) {
    if (!fill(1)) return stopped(0);
    const auto byte = static_cast<unsigned char>(buffer_[read_++]);
    length |= static_cast<std::uint64_t>(byte & 0x7f) << shift;
    if ((byte & 0x80) == 0) break;
    if (shift >= 63) {
      error_ = "recording '" + path_ + "': a record's length is not a varint";
      return false;
    }
  }
  constexpr std::uint64_t kMaxRecord = 512ull << 20;  // a scene with the largest meshes fits
  if (length > kMaxRecord) {
    error_ = "recording '" + path_ + "': a record claims " + std::to_string(length) + " bytes";
    return false;
  }
  if (!fill(static_cast<std::size_t>(length))) return stopped(base_ + read_ - start + length);
  if (!record.ParseFromArray(buffer_.get() + read_, static_cast<int>(length))) {
    error_ = "recording '" + path_ + "': a record does not parse";
    return false;
  }
  read_ += static_cast<std::size_t>(length);
  ++records_;
  offset_ = base_ + read_;
  return true;
}

}  // namespace haptic::recording
