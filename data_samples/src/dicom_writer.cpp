// The phantom as a DICOM CT series, written with GDCM (tests round-trip the DICOM reader with it).
#include <gdcmAttribute.h>
#include <gdcmImage.h>
#include <gdcmImageChangeTransferSyntax.h>
#include <gdcmImageWriter.h>
#include <gdcmMediaStorage.h>
#include <gdcmTrace.h>
#include <gdcmUIDGenerator.h>

#include <iomanip>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/data_samples/phantom.hpp"

namespace tactus::samples {

namespace {

template <std::uint16_t G, std::uint16_t E>
void put(gdcm::DataSet& ds, const std::string& value) {
  gdcm::DataElement de(gdcm::Tag(G, E));
  const gdcm::VR vr = gdcm::Attribute<G, E>::GetVR();
  de.SetVR(vr);
  std::string v = value;
  if (v.size() % 2) v += vr == gdcm::VR::UI ? '\0' : ' ';  // DICOM values have an even length
  de.SetByteValue(v.data(), static_cast<std::uint32_t>(v.size()));
  ds.Replace(de);
}

}  // namespace

void write_dicom_series(const Volume<std::int16_t>& ct, const std::filesystem::path& folder, const DicomSeriesOptions& o) {
  constexpr int kIntercept = -1024;
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) throw WriteError(folder.string(), "cannot create the folder (" + ec.message() + ")");
  gdcm::TransferSyntax syntax = gdcm::TransferSyntax::ExplicitVRLittleEndian;
  if (o.compression == "rle")
    syntax = gdcm::TransferSyntax::RLELossless;
  else if (o.compression == "jpeg-lossless")
    syntax = gdcm::TransferSyntax::JPEGLosslessProcess14_1;
  else if (o.compression != "none")
    throw InputError("command line", "--dicom-compression", "none, rle or jpeg-lossless", o.compression);
  gdcm::Trace::WarningOff();  // GDCM's notes on attributes it fills in itself, not the user's business
  gdcm::UIDGenerator uids;
  const std::string study = o.study_uid.empty() ? uids.Generate() : o.study_uid;
  const std::string series = o.series_uid.empty() ? uids.Generate() : o.series_uid;
  const std::string frame = uids.Generate();
  validate_direction(ct.direction, folder.string(), "direction");
  // Readers take the slice axis as row x column: of an orthonormal direction, that holds when it
  // is a rotation (det +1), not a reflection.
  if (determinant(ct.direction) < 0)
    throw InputError(folder.string(), "direction", "a rotation (the slice axis = row x column direction)", "a reflection");
  const int nx = ct.dims[0], ny = ct.dims[1], nz = ct.dims[2];
  std::vector<std::uint16_t> pixels(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        pixels[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i)] =
            static_cast<std::uint16_t>(ct.at(i, j, k) - kIntercept);
    gdcm::SmartPointer<gdcm::Image> image = new gdcm::Image;
    image->SetNumberOfDimensions(2);
    image->SetDimension(0, static_cast<unsigned int>(nx));
    image->SetDimension(1, static_cast<unsigned int>(ny));
    image->SetPixelFormat(gdcm::PixelFormat(1, 16, 16, 15, 0));  // unsigned 16 of 16 bits
    image->SetPhotometricInterpretation(gdcm::PhotometricInterpretation::MONOCHROME2);
    image->SetSpacing(0, ct.spacing[0] * 1e3);
    image->SetSpacing(1, ct.spacing[1] * 1e3);
    image->SetSpacing(2, ct.spacing[2] * 1e3);
    const Direction& D = ct.direction;
    double origin[3];
    for (int a = 0; a < 3; ++a) origin[a] = (ct.origin[a] + D[3 * static_cast<std::size_t>(a) + 2] * k * ct.spacing[2]) * 1e3;
    image->SetOrigin(origin);
    image->SetOrigin(2, origin[2]);  // a 2-D image keeps only two components of SetOrigin(double[3])
    const double cosines[6] = {D[0], D[3], D[6], D[1], D[4], D[7]};
    image->SetDirectionCosines(cosines);
    image->SetIntercept(kIntercept);
    image->SetSlope(1.0);
    gdcm::DataElement data(gdcm::Tag(0x7FE0, 0x0010));
    data.SetByteValue(reinterpret_cast<const char*>(pixels.data()), static_cast<std::uint32_t>(pixels.size() * sizeof(std::uint16_t)));
    image->SetDataElement(data);
    image->SetTransferSyntax(gdcm::TransferSyntax::ExplicitVRLittleEndian);
    gdcm::ImageWriter writer;
    if (syntax != gdcm::TransferSyntax::ExplicitVRLittleEndian) {
      gdcm::ImageChangeTransferSyntax change;
      change.SetTransferSyntax(syntax);
      change.SetInput(*image);
      if (!change.Change()) throw WriteError(folder.string(), "GDCM could not compress a slice (" + o.compression + ")");
      writer.SetImage(change.GetOutput());
    } else {
      writer.SetImage(*image);
    }
    gdcm::DataSet& ds = writer.GetFile().GetDataSet();
    put<0x0008, 0x0016>(ds, gdcm::MediaStorage::GetMSString(gdcm::MediaStorage::CTImageStorage));
    put<0x0008, 0x0018>(ds, uids.Generate());
    put<0x0008, 0x0008>(ds, "ORIGINAL\\PRIMARY\\AXIAL");
    put<0x0008, 0x0020>(ds, "20261130");
    put<0x0008, 0x0030>(ds, "120000");
    put<0x0008, 0x0050>(ds, "");
    put<0x0008, 0x0060>(ds, "CT");
    put<0x0008, 0x0070>(ds, "tactus");
    put<0x0008, 0x0090>(ds, "");
    put<0x0008, 0x103E>(ds, o.description);
    put<0x0010, 0x0010>(ds, "Phantom^Hand");
    put<0x0010, 0x0020>(ds, "TACTUS-PHANTOM");
    put<0x0010, 0x0030>(ds, "");
    put<0x0010, 0x0040>(ds, "O");
    put<0x0018, 0x0050>(ds, std::to_string(ct.spacing[2] * 1e3));
    put<0x0018, 0x0060>(ds, "120");
    put<0x0018, 0x5100>(ds, "HFS");
    put<0x0020, 0x000D>(ds, study);
    put<0x0020, 0x000E>(ds, series);
    put<0x0020, 0x0010>(ds, "1");
    put<0x0020, 0x0011>(ds, std::to_string(o.series_number));
    put<0x0020, 0x0012>(ds, "1");
    put<0x0020, 0x0013>(ds, std::to_string(k + 1));
    put<0x0020, 0x0052>(ds, frame);
    put<0x0020, 0x0060>(ds, "R");  // a hand is a paired body part: laterality is required
    put<0x0020, 0x1040>(ds, "");
    put<0x0028, 0x1054>(ds, "HU");
    std::ostringstream name;
    name << "IM_" << std::setw(4) << std::setfill('0') << k + 1 << ".dcm";
    writer.SetFileName((folder / name.str()).string().c_str());
    if (!writer.Write()) throw WriteError((folder / name.str()).string(), "GDCM could not write the slice");
  }
}

}  // namespace tactus::samples
