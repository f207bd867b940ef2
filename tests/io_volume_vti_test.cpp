// VTK XML ImageData (.vti) reader tests: ascii, inline base64 (header encoded separately or
// together with the data), zlib blocks, appended raw and base64 data, UInt32/UInt64 headers,
// both byte orders, WholeExtent start, Direction, and bad input.
#include "io_volume_test_util.h"

namespace adamesh {
namespace {

using namespace testutil;

std::string base64(const std::string& in) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const unsigned v = (unsigned char)in[i] << 16 | (unsigned char)in[i + 1] << 8 | (unsigned char)in[i + 2];
    out += {t[v >> 18], t[(v >> 12) & 63], t[(v >> 6) & 63], t[v & 63]};
  }
  if (i + 1 == in.size()) {
    const unsigned v = (unsigned char)in[i] << 16;
    out += {t[v >> 18], t[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == in.size()) {
    const unsigned v = (unsigned char)in[i] << 16 | (unsigned char)in[i + 1] << 8;
    out += {t[v >> 18], t[(v >> 12) & 63], t[(v >> 6) & 63], '='};
  }
  return out;
}

/// Header word in the file's byte order.
std::string word(std::uint64_t v, bool u64, bool big) {
  return u64 ? pod_bytes<std::uint64_t>(v, big) : pod_bytes<std::uint32_t>(static_cast<std::uint32_t>(v), big);
}

/// zlib blocks of `block` bytes: {header bytes, concatenated compressed blocks}.
std::pair<std::string, std::string> zblocks(const std::string& data, std::size_t block, bool u64, bool big) {
  std::string header, body;
  const std::size_t n = (data.size() + block - 1) / block;
  header = word(n, u64, big) + word(block, u64, big) + word(data.size() % block, u64, big);
  for (std::size_t b = 0; b < n; ++b) {
    const std::string z = compress(data.substr(b * block, block));
    header += word(z.size(), u64, big);
    body += z;
  }
  return {header, body};
}

std::string vti(const std::string& file_attrs, const std::string& image_attrs, const std::string& point_data,
                const std::string& appended = "") {
  return "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" " + file_attrs +
         ">\n  <ImageData " + image_attrs + ">\n  <Piece Extent=\"" +
         image_attrs.substr(image_attrs.find("WholeExtent=\"") + 13,
                            image_attrs.find('"', image_attrs.find("WholeExtent=\"") + 13) -
                                image_attrs.find("WholeExtent=\"") - 13) +
         "\">\n    <PointData Scalars=\"s\">\n" + point_data + "    </PointData>\n  </Piece>\n  </ImageData>\n" +
         appended + "</VTKFile>\n";
}

TEST(VtiRead, AsciiWithDirectionExtentStartOriginSpacing) {
  TempDir tmp;
  const std::string path = tmp.file("a.vti");
  write_bytes(path, vti("byte_order=\"LittleEndian\"",
                        "WholeExtent=\"1 2 0 1 -1 0\" Origin=\"10 20 30\" Spacing=\"2 3 4\" "
                        "Direction=\"0 -1 0 1 0 0 0 0 1\"",
                        "<DataArray type=\"Int16\" Name=\"s\" format=\"ascii\">\n -1 2 3\n 4 5 6 7 -8\n</DataArray>\n"));
  const Volume v = read_volume(path);
  EXPECT_EQ(v.format, "VTK XML ImageData");
  EXPECT_EQ(v.grid.dims, (std::array<std::int64_t, 3>{2, 2, 2}));
  expect_vec(v.grid.spacing, {2, 3, 4});
  // Row-major Direction: columns (0,1,0), (-1,0,0), (0,0,1).
  expect_mat(v.grid.direction, Mat3::from_columns({0, 1, 0}, {-1, 0, 0}, {0, 0, 1}));
  // Sample 0 is extent index (1, 0, -1): origin + D·(2·1, 3·0, 4·(-1)).
  expect_vec(v.grid.origin, {10, 20 + 2, 30 - 4});
  expect_samples(v, std::vector<int>{-1, 2, 3, 4, 5, 6, 7, -8});
}

TEST(VtiRead, InlineBinaryHeaderSeparateOrTogether) {
  TempDir tmp;
  const auto values = ramp<float>(3 * 2 * 2, -2, 0.5);
  const std::string data = to_bytes(values);
  const std::string image = "WholeExtent=\"0 2 0 1 0 1\" Origin=\"0 0 0\" Spacing=\"1 1 1\"";
  const std::string path = tmp.file("b.vti");
  // UInt32 header encoded on its own, as VTK writes it.
  write_bytes(path, vti("byte_order=\"LittleEndian\" header_type=\"UInt32\"", image,
                        "<DataArray type=\"Float32\" Name=\"s\" format=\"binary\">\n" +
                            base64(word(data.size(), false, false)) + base64(data) + "\n</DataArray>\n"));
  expect_samples(read_volume(path), values);
  // UInt64 header and data in one base64 stream, big-endian.
  write_bytes(path, vti("byte_order=\"BigEndian\" header_type=\"UInt64\"", image,
                        "<DataArray type=\"Float32\" Name=\"s\" format=\"binary\">" +
                            base64(word(data.size(), true, true) + to_bytes(values, true)) + "</DataArray>\n"));
  expect_samples(read_volume(path), values);
}

TEST(VtiRead, ZlibBlocksUInt32AndUInt64BothByteOrders) {
  TempDir tmp;
  const auto values = ramp<std::uint16_t>(5 * 4 * 3, 10, 97);  // 120 bytes: blocks of 50 → 50, 50, 20
  const std::string image = "WholeExtent=\"0 4 0 3 0 2\"";
  const std::string path = tmp.file("z.vti");
  for (bool u64 : {false, true}) {
    for (bool big : {false, true}) {
      const auto [header, body] = zblocks(to_bytes(values, big), 50, u64, big);
      write_bytes(path, vti(std::string("compressor=\"vtkZLibDataCompressor\" byte_order=\"") +
                                (big ? "BigEndian" : "LittleEndian") + "\"" +
                                (u64 ? " header_type=\"UInt64\"" : ""),
                            image,
                            "<DataArray type=\"UInt16\" Name=\"s\" format=\"binary\">\n" + base64(header) +
                                base64(body) + "\n</DataArray>\n"));
      SCOPED_TRACE(std::string(u64 ? "UInt64" : "UInt32") + (big ? " big" : " little"));
      expect_samples(read_volume(path), values);
    }
  }
}

TEST(VtiRead, AppendedRawAndBase64WithScalarsAttribute) {
  TempDir tmp;
  const auto first = ramp<std::int32_t>(8, 100, 1);
  const auto values = ramp<double>(8, -0.5, 0.125);
  const std::string image = "WholeExtent=\"0 1 0 1 0 1\"";
  // Raw: array "other" at offset 0, array "s" (compressed) after it.
  const std::string a = word(32, false, false) + to_bytes(first);
  const auto [header, body] = zblocks(to_bytes(values), 24, false, false);
  const std::string raw_path = tmp.file("r.vti");
  write_bytes(raw_path, vti("compressor=\"vtkZLibDataCompressor\" byte_order=\"LittleEndian\"", image,
                            "<DataArray type=\"Int32\" Name=\"other\" format=\"appended\" offset=\"0\"/>\n"
                            "<DataArray type=\"Float64\" Name=\"s\" format=\"appended\" offset=\"" +
                                std::to_string(a.size()) + "\"/>\n",
                            "<AppendedData encoding=\"raw\">\n   _" + a + header + body + "\n</AppendedData>\n"));
  expect_samples(read_volume(raw_path), values);
  // Uncompressed raw.
  const std::string plain = tmp.file("p.vti");
  write_bytes(plain, vti("byte_order=\"LittleEndian\"", image,
                         "<DataArray type=\"Float64\" Name=\"s\" format=\"appended\" offset=\"0\"/>\n",
                         "<AppendedData encoding=\"raw\">_" + word(64, false, false) + to_bytes(values) +
                             "</AppendedData>\n"));
  expect_samples(read_volume(plain), values);
  // Base64 appended: offsets count base64 characters.
  const std::string e1 = base64(word(32, false, false)) + base64(to_bytes(first));
  const std::string b64_path = tmp.file("e.vti");
  write_bytes(b64_path, vti("byte_order=\"LittleEndian\"", image,
                            "<DataArray type=\"Int32\" Name=\"other\" format=\"appended\" offset=\"0\"/>\n"
                            "<DataArray type=\"Float64\" Name=\"s\" format=\"appended\" offset=\"" +
                                std::to_string(e1.size()) + "\"/>\n",
                            "<AppendedData encoding=\"base64\">_" + e1 + base64(word(64, false, false)) +
                                base64(to_bytes(values)) + "</AppendedData>\n"));
  expect_samples(read_volume(b64_path), values);
}

class VtiBad : public ::testing::Test {
 protected:
  std::string write(const std::string& text) {
    const std::string path = tmp.file("bad.vti");
    write_bytes(path, text);
    return path;
  }
  TempDir tmp;
  const std::string image = "WholeExtent=\"0 1 0 1 0 1\"";
};

TEST_F(VtiBad, BadBase64AndCorruptZlib) {
  expect_read_error(write(vti("", image, "<DataArray type=\"UInt8\" Name=\"s\" format=\"binary\">CAAAAA==AQID*AUGBwg=</DataArray>")),
                    Status::invalid_input, {"bad base64 data", "'*'"});
  auto [header, body] = zblocks(std::string(8, 'v'), 8, false, false);
  body[3] = static_cast<char>(body[3] ^ 0x5a);
  body[4] = static_cast<char>(body[4] ^ 0x5a);
  expect_read_error(write(vti("compressor=\"vtkZLibDataCompressor\"", image,
                              "<DataArray type=\"UInt8\" Name=\"s\" format=\"binary\">" + base64(header) +
                                  base64(body) + "</DataArray>")),
                    Status::invalid_input, {"block 0", "compressed data"});
}

TEST_F(VtiBad, SizeMismatchAndTruncation) {
  expect_read_error(write(vti("", image, "<DataArray type=\"UInt8\" Name=\"s\" format=\"binary\">" +
                                             base64(word(7, false, false) + std::string(7, 'x')) + "</DataArray>")),
                    Status::invalid_input, {"holds 7 bytes, the extent needs 8"});
  expect_read_error(write(vti("", image, "<DataArray type=\"UInt8\" Name=\"s\" format=\"binary\">" +
                                             base64(word(8, false, false) + std::string(5, 'x')) + "</DataArray>")),
                    Status::invalid_input, {"truncated"});
  const auto [header, body] = zblocks(std::string(6, 'v'), 4, false, false);
  expect_read_error(write(vti("compressor=\"vtkZLibDataCompressor\"", image,
                              "<DataArray type=\"UInt8\" Name=\"s\" format=\"binary\">" + base64(header) +
                                  base64(body) + "</DataArray>")),
                    Status::invalid_input, {"describes 6 bytes, the extent needs 8"});
  std::string cut = vti("", image, "<DataArray type=\"UInt8\" Name=\"s\" format=\"appended\" offset=\"0\"/>",
                        "<AppendedData encoding=\"raw\">_" + word(8, false, false) + "abc");
  cut.resize(cut.find("abc") + 3);  // the file ends inside the appended data
  expect_read_error(write(cut), Status::invalid_input, {"truncated"});
  expect_read_error(write(vti("", "WholeExtent=\"0 1 0 -1 0 1\"", "<DataArray type=\"UInt8\" Name=\"s\" format=\"ascii\">1</DataArray>")),
                    Status::invalid_input, {"2x0x2", "at least 1"});
}

TEST_F(VtiBad, UnsupportedAndMalformed) {
  expect_read_error(write(vti("compressor=\"vtkLZ4DataCompressor\"", image, "")), Status::unsupported, {"vtkLZ4DataCompressor"});
  expect_read_error(write(vti("", image, "<DataArray type=\"Int64\" Name=\"s\" format=\"ascii\">1 2 3 4 5 6 7 8</DataArray>")),
                    Status::unsupported, {"Int64"});
  expect_read_error(write(vti("", image, "<DataArray type=\"Float32\" Name=\"s\" NumberOfComponents=\"3\" format=\"ascii\">1</DataArray>")),
                    Status::unsupported, {"3 components"});
  expect_read_error(write("<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\"></VTKFile>"), Status::unsupported, {"PolyData"});
  expect_read_error(write("<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\"><ImageData></VTKFile>"),
                    Status::invalid_input, {"malformed XML"});
  expect_read_error(write(vti("", "WholeExtent=\"0 1 0 x 0 1\"", "")), Status::invalid_input,
                    {"non-numeric value 'x' for WholeExtent"});
  expect_read_error(write(vti("", image, "")), Status::invalid_input, {"no PointData DataArray"});
}

}  // namespace
}  // namespace adamesh
