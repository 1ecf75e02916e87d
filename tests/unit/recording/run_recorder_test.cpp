// The recorder and its file: records read back as written (zstd, delimited), with buffers reused; a
// file cut short reads to its last whole record and says where; damage is named; recording every
// tick adds no allocation to the ticking thread while its own thread keeps up; a failed write (a
// full disk) is counted and said.
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "recording/run_recorder.hpp"
#include "recording/recording_file.hpp"
#include "runtime/cartesian_model.hpp"
#include "runtime/simulated_point_mass_device.hpp"
#include "runtime/tick_runner.hpp"
#include "support/allocation_counter.hpp"
#include "support/zstd_blocks.hpp"

namespace haptic::recording {
namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("hapticd-" + name + "-" + std::to_string(::getpid()) + ".hrec"))
      .string();
}

v1::Record sample_record(std::uint64_t tick, double force) {
  v1::Record record;
  record.mutable_sample()->set_tick(tick);
  record.mutable_sample()->mutable_force()->set_z(force);
  return record;
}

TEST(RecordingFile, RecordsReadBackAsWrittenAcrossManyCompressionBlocks) {
  const std::string path = temp_path("roundtrip");
  {
    RecordingWriter writer(path);
    v1::Record header;
    header.mutable_header()->set_format("hapticd-recording");
    ASSERT_TRUE(writer.write(header));
    // 200,000 samples: several 64 kB blocks, values whose bits must survive (NaN, -0, denormals).
    for (std::uint64_t tick = 1; tick <= 200'000; ++tick) {
      const double force = tick == 7 ? -0.0 : tick == 8 ? 4.9e-324 : 1.0 / static_cast<double>(tick);
      ASSERT_TRUE(writer.write(sample_record(tick, force)));
    }
    ASSERT_TRUE(writer.close()) << writer.error();
  }
  RecordingReader reader(path);
  v1::Record record;
  ASSERT_TRUE(reader.next(record));
  EXPECT_EQ(record.header().format(), "hapticd-recording");
  for (std::uint64_t tick = 1; tick <= 200'000; ++tick) {
    ASSERT_TRUE(reader.next(record)) << tick << " " << reader.error();
    ASSERT_EQ(record.sample().tick(), tick);
    const double force = tick == 7 ? -0.0 : tick == 8 ? 4.9e-324 : 1.0 / static_cast<double>(tick);
    ASSERT_EQ(std::bit_cast<std::uint64_t>(record.sample().force().z()), std::bit_cast<std::uint64_t>(force));
  }
  EXPECT_FALSE(reader.next(record));
  EXPECT_EQ(reader.error(), "");  // a clean end
  std::filesystem::remove(path);
}

// The reader reuses its buffers: reading a record allocates what parsing it does and nothing more
// (no buffer per decompression step), and a record larger than the buffer still reads back whole.
TEST(RecordingFile, ReadingAllocatesNoMoreThanParsingDoes) {
  const std::string path = temp_path("reuse");
  const auto big = [](std::size_t size, char fill) {
    v1::Record record;
    record.mutable_change()->mutable_opened()->set_client_name(std::string(size, fill));
    return record;
  };
  {
    RecordingWriter writer(path);
    for (std::uint64_t tick = 1; tick <= 30'000; ++tick) {
      ASSERT_TRUE(writer.write(sample_record(tick, 1.0 / static_cast<double>(tick))));
    }
    ASSERT_TRUE(writer.write(big(300'000, 'a')));    // more than a block
    ASSERT_TRUE(writer.write(big(3'000'000, 'b')));  // more than the buffer
    for (std::uint64_t tick = 30'001; tick <= 40'000; ++tick) {
      ASSERT_TRUE(writer.write(sample_record(tick, 0.5)));
    }
    ASSERT_TRUE(writer.close()) << writer.error();
  }

  // What parsing a sample into a reused Record allocates (its oneof's message, the force).
  v1::Record record;
  const std::string serialized = sample_record(5, 0.25).SerializeAsString();
  ASSERT_TRUE(record.ParseFromString(serialized));
  test::reset_allocations();
  {
    test::CountAllocations counting;
    for (int i = 0; i < 1000; ++i) ASSERT_TRUE(record.ParseFromString(serialized));
  }
  const std::uint64_t per_parse = test::allocations() / 1000;

  RecordingReader reader(path);
  for (std::uint64_t tick = 1; tick <= 100; ++tick) ASSERT_TRUE(reader.next(record));  // buffers made
  test::reset_allocations();
  {
    test::CountAllocations counting;
    for (std::uint64_t tick = 101; tick <= 30'000; ++tick) {
      if (!reader.next(record) || record.sample().tick() != tick) break;
    }
  }
  EXPECT_EQ(record.sample().tick(), 30'000u) << reader.error();
  // 29,900 records through about 15 decompressed blocks: a buffer per block, let alone per
  // record, would show.
  EXPECT_LE(test::allocations(), 29'900 * per_parse) << per_parse << " a parse";

  ASSERT_TRUE(reader.next(record)) << reader.error();
  EXPECT_EQ(record.change().opened().client_name(), std::string(300'000, 'a'));
  ASSERT_TRUE(reader.next(record)) << reader.error();
  EXPECT_EQ(record.change().opened().client_name(), std::string(3'000'000, 'b'));
  for (std::uint64_t tick = 30'001; tick <= 40'000; ++tick) {
    ASSERT_TRUE(reader.next(record)) << reader.error();
    ASSERT_EQ(record.sample().tick(), tick);
  }
  EXPECT_FALSE(reader.next(record));
  EXPECT_EQ(reader.error(), "");
  std::filesystem::remove(path);
}


// A recording cut short (its writer killed): whatever the byte the file ends at, every whole record
// before it reads back as written, and the reader says it was cut short and where: right after a
// record, inside a compressed block, inside a record.
TEST(RecordingFile, ACutFileReadsToItsLastWholeRecordAndSaysWhere) {
  const std::string path = temp_path("whole");
  std::vector<v1::Record> written;
  std::vector<std::uint64_t> ends{0};  // where each record ends in the decompressed stream
  std::uintmax_t after_100 = 0;        // the file's size once the first 100 records were flushed
  std::uintmax_t after_big = 0;
  {
    RecordingWriter writer(path);
    const auto write = [&](const v1::Record& record) {
      const std::uint64_t size = record.ByteSizeLong();
      std::uint64_t varint = 1;
      while (size >> (7 * varint) != 0) ++varint;
      ends.push_back(ends.back() + varint + size);
      written.push_back(record);
      ASSERT_TRUE(writer.write(record));
    };
    for (std::uint64_t tick = 1; tick <= 100; ++tick) write(sample_record(tick, 2.0 / tick));
    ASSERT_TRUE(writer.flush());
    after_100 = std::filesystem::file_size(path);
    // A record of 400 kB that compresses little: several blocks.
    std::string name(400'000, ' ');
    std::uint32_t state = 12345;
    for (char& c : name) c = static_cast<char>('a' + ((state = state * 1103515245u + 12345u) >> 16) % 26);
    v1::Record big;
    big.mutable_change()->mutable_opened()->set_client_name(name);
    write(big);
    ASSERT_TRUE(writer.flush());
    after_big = std::filesystem::file_size(path);
    for (std::uint64_t tick = 101; tick <= 200; ++tick) write(sample_record(tick, 3.0 / tick));
    ASSERT_TRUE(writer.close()) << writer.error();
  }
  std::string bytes;
  {
    std::ifstream file(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(file), {});
  }
  ASSERT_EQ(bytes.size(), std::filesystem::file_size(path));

  struct Read {
    std::uint64_t records = 0;
    std::uint64_t offset = 0;
    bool cut_short = false;
    std::string error;
  };
  const std::string cut = temp_path("cut");
  const auto read_cut = [&](std::size_t size) {
    std::ofstream(cut, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(size));
    RecordingReader reader(cut);
    v1::Record record;
    Read read;
    while (reader.next(record)) {
      EXPECT_EQ(record.SerializeAsString(), written.at(read.records).SerializeAsString()) << read.records;
      ++read.records;
    }
    EXPECT_EQ(reader.records(), read.records);
    read.offset = reader.offset();
    read.cut_short = reader.cut_short();
    read.error = reader.error();
    return read;
  };
  const auto has = [](const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
  };

  // Right after a whole record: the file as the writer left it after a flush.
  Read read = read_cut(after_100);
  EXPECT_EQ(read.records, 100u);
  EXPECT_EQ(read.offset, ends[100]);
  EXPECT_TRUE(read.cut_short);
  EXPECT_TRUE(has(read.error, "the file ends in the middle of its compressed stream, at the end of a "
                              "block, after a whole record: cut short")) << read.error;

  // Inside a compressed block: its records are lost, not misread.
  read = read_cut(after_100 + 10);
  EXPECT_EQ(read.records, 100u);
  EXPECT_EQ(read.offset, ends[100]);
  EXPECT_TRUE(read.cut_short);
  EXPECT_TRUE(has(read.error, "ends in the middle of a compressed block (")) << read.error;

  // Inside a record: at the end of a block that holds the big record's beginning only.
  const std::vector<std::size_t> blocks = test::zstd_block_ends(bytes);
  const auto inside = std::find_if(blocks.begin(), blocks.end(),
                                   [&](std::size_t end) { return end > after_100 && end < after_big; });
  ASSERT_NE(inside, blocks.end());
  read = read_cut(*inside);
  EXPECT_EQ(read.records, 100u);
  EXPECT_TRUE(read.cut_short);
  EXPECT_TRUE(has(read.error, "at the end of a block, inside a record (")) << read.error;
  EXPECT_TRUE(has(read.error, " of its " + std::to_string(ends[101] - ends[100]) + " bytes are there)"))
      << read.error;
  read = read_cut(*inside + 7);  // and a few bytes into the next block
  EXPECT_EQ(read.records, 100u);
  EXPECT_TRUE(has(read.error, "ends in the middle of a compressed block (")) << read.error;
  EXPECT_TRUE(has(read.error, "what it holds is lost), inside a record (")) << read.error;

  // Nothing at all.
  read = read_cut(0);
  EXPECT_EQ(read.records, 0u);
  EXPECT_TRUE(read.cut_short);
  EXPECT_TRUE(has(read.error, "the file is empty")) << read.error;

  // Any byte (every 199th): whole records only, never fewer for more bytes, and always said to be cut short.
  std::uint64_t before = 0;
  for (std::size_t size = 1; size < bytes.size(); size += 199) {
    read = read_cut(size);
    EXPECT_GE(read.records, before) << size;
    EXPECT_EQ(read.offset, ends[read.records]) << size;
    EXPECT_TRUE(read.cut_short) << size;
    EXPECT_TRUE(has(read.error, "cut short")) << size << ": " << read.error;
    before = read.records;
  }
  read = read_cut(bytes.size());
  EXPECT_EQ(read.records, 201u);
  EXPECT_FALSE(read.cut_short);
  EXPECT_EQ(read.error, "");
  std::filesystem::remove(path);
  std::filesystem::remove(cut);
}

TEST(RecordingFile, DamageIsNamedNotMistakenForAnEnd) {
  const std::string path = temp_path("damaged");
  {
    RecordingWriter writer(path);
    for (std::uint64_t tick = 1; tick <= 50'000; ++tick) writer.write(sample_record(tick, 1.5));
    ASSERT_TRUE(writer.close());
  }
  // Cut in the middle: what is there reads, then the cut is reported.
  std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
  {
    RecordingReader reader(path);
    v1::Record record;
    std::uint64_t read = 0;
    while (reader.next(record)) ++read;
    EXPECT_GT(read, 0u);
    EXPECT_LT(read, 50'000u);
    EXPECT_NE(reader.error().find("ends in the middle"), std::string::npos) << reader.error();
  }
  // Not zstd at all.
  std::ofstream(path) << "{\"this\": \"is JSON\"}";
  {
    RecordingReader reader(path);
    v1::Record record;
    EXPECT_FALSE(reader.next(record));
    EXPECT_NE(reader.error().find("not a readable recording"), std::string::npos) << reader.error();
  }
  std::filesystem::remove(path);
  EXPECT_THROW(RecordingReader("/nonexistent/x.hrec"), std::runtime_error);
  EXPECT_THROW(RecordingWriter("/nonexistent/x.hrec"), std::runtime_error);
}

// The ticking thread publishes samples as always; the recorder's thread writes them. Ticking with
// a recording running allocates nothing, and every tick's sample is in the file exactly.
TEST(RunRecorder, EveryTickIsRecordedWithoutAllocatingOnTheTickingThread) {
  runtime::SimulatedPointMassDevice device(engine::PointMassParams{},
                                           engine::PointMassState{{0.0, 0.0, 0.01}, {}}, 20.0);
  runtime::CartesianModel model;
  runtime::SceneExchange scenes(std::make_unique<const engine::CompiledScene>());
  runtime::SampleRing ring;
  runtime::LoopCounters counters;
  runtime::TickRunner runner(device, model, scenes, ring, counters, runtime::TickConfig{0.001, {}, 50, {}});
  engine::HandInput push;
  push.mode = engine::HandInput::Mode::kApplyForce;
  push.force = {0.0, 0.0, -2.0};
  device.set_hand(push);

  std::atomic<std::uint64_t> completed{0};
  RunRecorder recorder([&] { return completed.load(); }, {&ring});
  const std::string path = temp_path("recorder");
  ASSERT_EQ(recorder.start(path, v1::ServerConfig{}), "");
  v1::RecordedChange change;
  change.mutable_opened()->set_client_name("tester");
  recorder.record(change);  // stamped after tick 0

  std::vector<runtime::TickSample> published;
  std::uint64_t inside = 0;
  for (std::uint64_t tick = 1; tick <= 5000; ++tick) {
    test::reset_allocations();
    {
      test::CountAllocations counting;
      runner.run(tick, static_cast<std::int64_t>(tick - 1) * 1'000'000);
      completed.store(tick);
    }
    inside += test::allocations();
    runtime::TickSample sample;
    ASSERT_TRUE(ring.read(tick, sample));
    published.push_back(sample);
    // The ring holds 1024: let the recorder keep up, as a lockstep Step does.
    if (tick % 500 == 0) {
      ASSERT_TRUE(recorder.wait_written_through(tick, std::chrono::seconds(5)));
    }
  }
  const auto end = recorder.stop("stopped");
  ASSERT_TRUE(end.has_value());
  EXPECT_EQ(inside, 0u);
  EXPECT_EQ(end->samples(), 5000u);
  EXPECT_EQ(end->samples_missed(), 0u);
  EXPECT_EQ(end->changes(), 1u);
  EXPECT_FALSE(recorder.active());

  RecordingReader reader(path);
  v1::Record record;
  ASSERT_TRUE(reader.next(record));
  ASSERT_TRUE(record.has_header());
  EXPECT_EQ(record.header().start_tick(), 0u);
  EXPECT_EQ(record.header().device_ports(), 1u);
  ASSERT_TRUE(reader.next(record));
  ASSERT_TRUE(record.has_change());  // before any sample: it took effect from tick 1
  EXPECT_EQ(record.change().after_tick(), 0u);
  EXPECT_EQ(record.change().opened().client_name(), "tester");
  for (const runtime::TickSample& sample : published) {
    ASSERT_TRUE(reader.next(record));
    ASSERT_TRUE(record.has_sample());
    ASSERT_EQ(record.sample().tick(), sample.tick);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(record.sample().force().z()),
              std::bit_cast<std::uint64_t>(sample.F_T_W.z));
    EXPECT_EQ(std::bit_cast<std::uint64_t>(record.sample().position().z()),
              std::bit_cast<std::uint64_t>(sample.p_WT.z));
  }
  ASSERT_TRUE(reader.next(record));
  EXPECT_EQ(record.end().stopped_because(), "stopped");
  EXPECT_FALSE(reader.next(record));
  std::filesystem::remove(path);

  // A second recording may follow; one at a time.
  ASSERT_EQ(recorder.start(path, v1::ServerConfig{}), "");
  EXPECT_EQ(recorder.start(path, v1::ServerConfig{}), "already recording to '" + path + "'");
  recorder.stop("stopped");
  std::filesystem::remove(path);
}

// A write that fails (a full disk: /dev/full fails every one with ENOSPC) is counted and said, at
// once in the log and at the end in the RecordEnd and the end line, not reported as "0 missed".
TEST(RunRecorder, AFailedWriteIsCountedAndReported) {
  std::ostringstream log_text;
  const auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>(
      "recorder-test", std::make_shared<spdlog::sinks::ostream_sink_mt>(log_text)));

  runtime::SampleRing ring;
  std::atomic<std::uint64_t> completed{0};
  RunRecorder recorder([&] { return completed.load(); }, {&ring});
  ASSERT_EQ(recorder.start("/dev/full", v1::ServerConfig{}), "");
  v1::RecordedChange change;
  change.mutable_opened()->set_client_name("tester");
  recorder.record(change);
  for (std::uint64_t tick = 1; tick <= 5000; ++tick) {
    runtime::TickSample sample;
    sample.tick = tick;
    sample.F_T_W = {0.0, 0.0, 1.0 / static_cast<double>(tick)};
    sample.p_WT = {0.001 * static_cast<double>(tick), 0.0, 0.0};
    ring.publish(sample);
    completed.store(tick);
    if (tick % 500 == 0) {
      ASSERT_TRUE(recorder.wait_written_through(tick, std::chrono::seconds(5)));
    }
  }
  const auto end = recorder.stop("stopped");
  spdlog::set_default_logger(previous);
  ASSERT_TRUE(end.has_value());
  EXPECT_EQ(end->samples(), 5000u);
  EXPECT_EQ(end->samples_missed(), 0u);  // the ring was read in time: what failed was the disk
  EXPECT_EQ(end->changes(), 1u);
  // Nothing reached the file: the header, the change, 5000 samples and the end record.
  EXPECT_EQ(end->records_not_written(), 5003u);
  EXPECT_EQ(end->write_error(), "writing '/dev/full': No space left on device");
  const std::string said = log_text.str();
  EXPECT_NE(said.find("recording '/dev/full': writing '/dev/full': No space left on device: nothing "
                      "more is written to it"),
            std::string::npos)
      << said;
  EXPECT_NE(said.find("recording '/dev/full' stopped: 5000 samples (0 missed), 1 changes; 5003 "
                      "records not written (writing '/dev/full': No space left on device)"),
            std::string::npos)
      << said;
}

// A recording whose disk fills midway: what was handed to the file before reads back, the rest is
// counted. (The file is cut short then: hapticd --replay says so.)
TEST(RecordingFile, RecordsAfterAFailedWriteAreCountedNotWritten) {
  RecordingWriter writer("/dev/full");
  EXPECT_EQ(writer.records_not_written(), 0u);
  ASSERT_TRUE(writer.write(sample_record(1, 1.0)));  // gathered, not yet handed to the file
  EXPECT_FALSE(writer.flush());
  EXPECT_EQ(writer.error(), "writing '/dev/full': No space left on device");
  EXPECT_FALSE(writer.write(sample_record(2, 1.0)));
  EXPECT_FALSE(writer.write(sample_record(3, 1.0)));
  EXPECT_EQ(writer.records_not_written(), 3u);
  EXPECT_FALSE(writer.close());
  EXPECT_EQ(writer.records_not_written(), 3u);
  EXPECT_EQ(writer.error(), "writing '/dev/full': No space left on device");  // the first error
}

}  // namespace
}  // namespace haptic::recording
