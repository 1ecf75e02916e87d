#pragma once
// The recording file (haptic/v1/recording.proto): a zstd stream of length-delimited Record
// messages. The writer is used by one thread (the recorder's); the reader streams, so a long
// recording is never held whole in memory.
//
// A recording cut short (its writer killed, or the machine) is a zstd frame that never ends. The
// writer hands the file whole blocks of whole records (every 64 kB of records, and on flush()), so
// such a file usually ends right after a record; the reader reads up to the last whole record
// wherever the file ends, and says where that was (cut_short(), records(), offset(), error()).

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

#include "haptic/v1/recording.pb.h"

struct ZSTD_CCtx_s;
struct ZSTD_DCtx_s;

namespace haptic::recording {

class RecordingWriter {
 public:
  /// Creates (truncates) `path`. Throws std::runtime_error naming the file and why.
  explicit RecordingWriter(const std::string& path);
  ~RecordingWriter();  // finishes the stream and closes the file (close() first to see errors)
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  /// Appends one record; false (and error() says why) once a write has failed: after one, nothing
  /// more is written (the compressed stream is broken there), and records_not_written() counts.
  bool write(const v1::Record& record);
  /// Hands the records written so far to the file, as whole compressed blocks: were the writer
  /// killed now, they could be read back. false once a write has failed.
  bool flush();
  /// Ends the zstd frame and closes the file; false if anything failed.
  bool close();
  const std::string& error() const { return error_; }
  const std::string& path() const { return path_; }
  /// Records given to write() that are not in the file because a write failed: those not yet
  /// handed to the file by a flush that succeeded. 0 while none has failed.
  std::uint64_t records_not_written() const { return error_.empty() ? 0 : offered_ - in_file_; }

 private:
  enum class Directive { kFlush, kEnd };  // kFlush: whole blocks; kEnd: the frame's end too
  /// Compresses and writes `pending_`, then empties it.
  bool compress(Directive directive);

  std::string path_;
  std::FILE* file_ = nullptr;
  ZSTD_CCtx_s* context_ = nullptr;
  std::string pending_;   // records gathered before compression (a few kB at a time)
  std::uint64_t offered_ = 0;  // records given to write()
  std::uint64_t pending_records_ = 0;  // of those, in pending_
  std::uint64_t in_file_ = 0;  // of those, handed to the file by a flush that succeeded
  std::string out_;       // compressed bytes
  std::string error_;
};

class RecordingReader {
 public:
  /// Opens `path`. Throws std::runtime_error naming the file and why.
  explicit RecordingReader(const std::string& path);
  ~RecordingReader();
  RecordingReader(const RecordingReader&) = delete;
  RecordingReader& operator=(const RecordingReader&) = delete;

  /// The next record; false at the end of the file or on an error (error() is then not empty:
  /// a truncated file, bytes that are not zstd, a record that does not parse).
  bool next(v1::Record& record);
  const std::string& error() const { return error_; }
  /// The file just stops, mid-frame or mid-record, as when its writer was killed (or is empty):
  /// every whole record before that was read. Not set for damage (bytes that are not zstd, a
  /// checksum that does not match, a record that does not parse).
  bool cut_short() const { return cut_short_; }
  /// Whole records read so far.
  std::uint64_t records() const { return records_; }
  /// The bytes those records take in the decompressed stream: where the next one begins.
  std::uint64_t offset() const { return offset_; }
  /// Bytes read from the file so far (all of it, once next() has returned false).
  std::uint64_t file_bytes() const { return file_bytes_; }

 private:
  /// Decompresses until the buffer holds at least `bytes` unread bytes; false at the end. Reuses
  /// its buffers: it allocates only for a record larger than any before.
  bool fill(std::size_t bytes);

  std::string path_;
  std::FILE* file_ = nullptr;
  ZSTD_DCtx_s* context_ = nullptr;
  std::unique_ptr<char[]> in_;      // compressed bytes read from the file
  std::size_t in_capacity_ = 0;
  std::size_t in_size_ = 0;         // of in_, read from the file
  std::size_t in_used_ = 0;         // of those, decompressed
  std::unique_ptr<char[]> buffer_;  // decompressed bytes
  std::size_t capacity_ = 0;
  std::size_t size_ = 0;            // of buffer_, decompressed
  std::size_t read_ = 0;            // of those, consumed
  std::uint64_t base_ = 0;          // decompressed bytes before buffer_[0]
  std::uint64_t file_bytes_ = 0;    // compressed bytes read from the file
  std::size_t hint_ = 0;            // the last decompression's hint: the input it wants next
  std::uint64_t records_ = 0;
  std::uint64_t offset_ = 0;
  bool file_done_ = false;
  bool frame_done_ = true; // the last decompress call ended a frame (a file may end there)
  bool cut_short_ = false;
  std::string error_;
};

}  // namespace haptic::recording
