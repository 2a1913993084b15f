// SPDX-License-Identifier: BSD-3-Clause
#include "vtkDPXMLReaders.h"

#include "vtkObjectFactory.h"
#include "vtkXMLDataParser.h"

#include <expat.h>

namespace
{
// A vtkXMLDataParser whose expat parser has reparse deferral switched off.
class DeferralFreeDataParser : public vtkXMLDataParser
{
public:
  static DeferralFreeDataParser* New();
  vtkTypeMacro(DeferralFreeDataParser, vtkXMLDataParser);

protected:
  int CreateParser() override
  {
    const int created = this->Superclass::CreateParser();
#ifdef DYNAMICPOINTS_HAVE_EXPAT_REPARSE_DEFERRAL
    if (created && this->Parser)
    {
      XML_SetReparseDeferralEnabled(static_cast<XML_Parser>(this->Parser), XML_FALSE);
    }
#endif
    return created;
  }
};
vtkStandardNewMacro(DeferralFreeDataParser);

// Swaps the parser vtkXMLReader::CreateXMLParser() made for one that parses appended data.
void replaceParser(vtkXMLDataParser*& parser)
{
  if (parser)
  {
    parser->Delete();
  }
  parser = DeferralFreeDataParser::New();
}
} // namespace

vtkStandardNewMacro(vtkDPXMLPolyDataReader);
vtkStandardNewMacro(vtkDPXMLUnstructuredGridReader);

void vtkDPXMLPolyDataReader::CreateXMLParser()
{
  this->Superclass::CreateXMLParser();
  replaceParser(this->XMLParser);
}

void vtkDPXMLUnstructuredGridReader::CreateXMLParser()
{
  this->Superclass::CreateXMLParser();
  replaceParser(this->XMLParser);
}
