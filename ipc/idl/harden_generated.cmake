# Run after fastddsgen (ipc/CMakeLists.txt) on the C++ it generated: two fixes of what fastddsgen 2.x (Debian 12)
# writes, both found by the dds_sample fuzz target (test/fuzz) and tested in test/unit/dds/correlator_dds_test.cpp.
# 1. The element count of a sequence of strings: its deserialize() resized the vector to the count a sample declares
#    before reading the elements, without the IDL's bound (2^31 strings: 68 GB asked for, an out-of-memory crash of
#    any reader). fastcdr's own sequence reader checks a count against the bytes left; this refuses counts above
#    kMaxStrings (at least every IDL bound of a string sequence: 64 today) as a short sample is refused.
# 2. A PubSubType's deserialize() caught only NotEnoughMemoryException: a bad encapsulation or bool made fastcdr
#    throw BadParamException out of the reader (std::terminate). It now catches fastcdr's base exception: the sample
#    is refused (deserialize() returns false).
# Usage: cmake -DFILES="a.cxx;b.cxx" -P harden_generated.cmake
set(kMaxStrings 4096)
foreach(file IN LISTS FILES)
    file(READ "${file}" text)
    string(REGEX REPLACE
        "dcdr >> sequence_size;\n( *)(m_[A-Za-z0-9_]+)\\.resize\\(sequence_size\\);"
        "dcdr >> sequence_size;\n\\1if (sequence_size > ${kMaxStrings}U) // harden_generated.cmake\n\\1{\n\\1    throw eprosima::fastcdr::exception::NotEnoughMemoryException(eprosima::fastcdr::exception::NotEnoughMemoryException::NOT_ENOUGH_MEMORY_MESSAGE_DEFAULT);\n\\1}\n\\1\\2.resize(sequence_size);"
        text "${text}")
    string(REPLACE "catch (eprosima::fastcdr::exception::NotEnoughMemoryException& /*exception*/)"
           "catch (eprosima::fastcdr::exception::Exception& /*exception*/) // harden_generated.cmake" text "${text}")
    string(REPLACE "#include <fastcdr/Cdr.h>\n" "#include <fastcdr/Cdr.h>\n#include <fastcdr/exceptions/NotEnoughMemoryException.h>\n"
           text "${text}")
    file(WRITE "${file}" "${text}")
endforeach()
