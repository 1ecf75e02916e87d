#pragma once
// The session recorder's files read back (docs/recorder.md): CSV and HDF5 as rows of named
// columns, for the tests that compare them with what a callback saw (C++, C, C#).

#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <haptic/haptic.hpp>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace haptic::test {

/// A fresh folder for one test's files, removed at the end.
class TempDir {
 public:
  TempDir() {
    static int counter = 0;
    path_ = std::filesystem::temp_directory_path() /
            ("hapticd-recorder-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string path() const { return path_.string(); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  std::size_t entries() const {
    return static_cast<std::size_t>(
        std::distance(std::filesystem::directory_iterator(path_), std::filesystem::directory_iterator()));
  }

 private:
  std::filesystem::path path_;
};

/// A CSV file as its header and rows of fields (RFC 4180 quotes handled).
struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::size_t column(const std::string& name) const {
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (header[i] == name) return i;
    }
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
};

inline std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        fields.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  return fields;
}

inline Csv read_csv(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << "cannot read " << path;
  Csv csv;
  std::string line;
  if (std::getline(in, line)) csv.header = split_csv_line(line);
  while (std::getline(in, line)) {
    csv.rows.push_back(split_csv_line(line));
    EXPECT_EQ(csv.rows.back().size(), csv.header.size()) << "row " << csv.rows.size() << ": " << line;
  }
  return csv;
}

inline double csv_double(const std::string& text) { return text == "NaN" ? std::nan("") : std::stod(text); }

/// The same double, NaN included (absent orientation and torque are NaN).
inline bool same(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

/// One sample as both files hold it: every column as a double or an integer, by column name.
struct Row {
  std::map<std::string, double> real;
  std::map<std::string, std::int64_t> integer;
};

inline constexpr const char* kDoubleColumns[] = {
    "server_time_s", "position_x_m",   "position_y_m",   "position_z_m",  "velocity_x_m_s",
    "velocity_y_m_s", "velocity_z_m_s", "force_x_N",      "force_y_N",     "force_z_N",
    "proxy_x_m",     "proxy_y_m",      "proxy_z_m",      "orientation_w", "orientation_x",
    "orientation_y", "orientation_z",  "torque_x_Nm",    "torque_y_Nm",   "torque_z_Nm"};
inline constexpr const char* kIntegerColumns[] = {"received_ns", "arrived_ns", "tick",  "sequence",
                                           "contact_count", "flags",    "buttons", "age_ns"};

/// What a State must read back as.
inline Row expected_row(const State& s) {
  const double nan = std::nan("");
  const auto ns = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
  };
  Row row;
  row.real = {{"server_time_s", s.server_time},
              {"position_x_m", s.position.x},   {"position_y_m", s.position.y},   {"position_z_m", s.position.z},
              {"velocity_x_m_s", s.velocity.x}, {"velocity_y_m_s", s.velocity.y}, {"velocity_z_m_s", s.velocity.z},
              {"force_x_N", s.force.x},         {"force_y_N", s.force.y},         {"force_z_N", s.force.z},
              {"proxy_x_m", s.proxy.x},         {"proxy_y_m", s.proxy.y},         {"proxy_z_m", s.proxy.z},
              {"orientation_w", s.orientation ? s.orientation->w : nan},
              {"orientation_x", s.orientation ? s.orientation->x : nan},
              {"orientation_y", s.orientation ? s.orientation->y : nan},
              {"orientation_z", s.orientation ? s.orientation->z : nan},
              {"torque_x_Nm", s.torque ? s.torque->x : nan},
              {"torque_y_Nm", s.torque ? s.torque->y : nan},
              {"torque_z_Nm", s.torque ? s.torque->z : nan}};
  row.integer = {{"received_ns", ns(s.received_at)},
                 {"arrived_ns", s.arrived_at ? ns(*s.arrived_at) : -1},
                 {"tick", static_cast<std::int64_t>(s.tick)},
                 {"sequence", static_cast<std::int64_t>(s.sequence)},
                 {"contact_count", s.contact_count},
                 {"flags", s.flags},
                 {"buttons", s.buttons},
                 {"age_ns", s.age.count()}};
  return row;
}

inline std::vector<Row> csv_rows(const Csv& csv) {
  std::vector<Row> rows(csv.rows.size());
  for (const char* name : kDoubleColumns) {
    const std::size_t c = csv.column(name);
    for (std::size_t r = 0; r < rows.size(); ++r) rows[r].real[name] = csv_double(csv.rows[r][c]);
  }
  for (const char* name : kIntegerColumns) {
    const std::size_t c = csv.column(name);
    for (std::size_t r = 0; r < rows.size(); ++r) rows[r].integer[name] = std::stoll(csv.rows[r][c]);
  }
  return rows;
}

/// A 1-D dataset of `path` read as `memory_type` (HDF5 converts).
template <typename T>
std::vector<T> h5_column(hid_t file, const std::string& path, hid_t memory_type) {
  const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  EXPECT_GE(set, 0) << "no dataset " << path;
  if (set < 0) return {};
  const hid_t space = H5Dget_space(set);
  hsize_t n = 0;
  H5Sget_simple_extent_dims(space, &n, nullptr);
  std::vector<T> values(n);
  if (n > 0) {
    EXPECT_GE(H5Dread(set, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
  }
  H5Sclose(space);
  H5Dclose(set);
  return values;
}

inline std::vector<std::string> h5_strings(hid_t file, const std::string& path) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, H5T_VARIABLE);
  H5Tset_cset(type, H5T_CSET_UTF8);
  std::vector<char*> raw = h5_column<char*>(file, path, type);
  std::vector<std::string> out;
  for (char* text : raw) {
    out.emplace_back(text != nullptr ? text : "");
    H5free_memory(text);
  }
  H5Tclose(type);
  return out;
}

/// A string attribute of the object at `object` ("/" for the file's own).
inline std::string h5_text_attribute(hid_t file, const std::string& object, const std::string& name) {
  const hid_t attribute = H5Aopen_by_name(file, object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  EXPECT_GE(attribute, 0) << "no attribute " << object << " " << name;
  if (attribute < 0) return {};
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, H5T_VARIABLE);
  H5Tset_cset(type, H5T_CSET_UTF8);
  char* text = nullptr;
  EXPECT_GE(H5Aread(attribute, type, &text), 0);
  std::string out = text != nullptr ? text : "";
  H5free_memory(text);
  H5Tclose(type);
  H5Aclose(attribute);
  return out;
}

inline std::vector<Row> h5_rows(hid_t file) {
  std::vector<Row> rows;
  for (const char* name : kDoubleColumns) {
    const auto values = h5_column<double>(file, std::string("/samples/") + name, H5T_NATIVE_DOUBLE);
    rows.resize(values.size());
    for (std::size_t r = 0; r < values.size(); ++r) rows[r].real[name] = values[r];
  }
  for (const char* name : kIntegerColumns) {
    const auto values = h5_column<std::int64_t>(file, std::string("/samples/") + name, H5T_NATIVE_INT64);
    EXPECT_EQ(values.size(), rows.size()) << name;
    for (std::size_t r = 0; r < values.size() && r < rows.size(); ++r) rows[r].integer[name] = values[r];
  }
  return rows;
}

/// Every row of `seen` (what a callback saw, as a CSV in the recorder's columns) is in `rows` (a
/// recorder's file) by tick, with every column the same.
inline void expect_rows_match(const std::vector<Row>& rows, const std::vector<Row>& seen, const std::string& what) {
  std::map<std::int64_t, const Row*> by_tick;
  for (const Row& row : rows) by_tick[row.integer.at("tick")] = &row;
  ASSERT_FALSE(seen.empty()) << what << ": the callback saw nothing";
  for (const Row& want : seen) {
    const std::int64_t tick = want.integer.at("tick");
    const auto found = by_tick.find(tick);
    ASSERT_NE(found, by_tick.end()) << what << ": no row for tick " << tick;
    for (const auto& [name, value] : want.real) {
      EXPECT_TRUE(same(found->second->real.at(name), value))
          << what << " tick " << tick << " " << name << ": " << found->second->real.at(name) << " vs " << value;
    }
    for (const auto& [name, value] : want.integer) {
      EXPECT_EQ(found->second->integer.at(name), value) << what << " tick " << tick << " " << name;
    }
  }
}

/// A recorder's HDF5 file's samples as rows.
inline std::vector<Row> h5_file_rows(const std::string& path) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(file, 0) << "cannot open " << path;
  if (file < 0) return {};
  std::vector<Row> rows = h5_rows(file);
  H5Fclose(file);
  return rows;
}

}  // namespace haptic::test
