# Post-processes fastddsgen 2.3's output (cmake -P, run by idl/CMakeLists.txt right after the
# generator; the generated files stay in the build tree, never committed).
#
# 1. Type objects are registered once per process, not once per sample. With -typeobject every
#    constructor of every generated type calls register<idl>Types(), which adds the type objects
#    of all types of the file to Fast DDS's TypeObjectFactory again: ~20 us per sample
#    constructed. The constructors lose the call and register<idl>Types() runs its body once.
# 2. Whether the types are announced in discovery (TYPE_OBJECTS, OFF by default):
#    - OFF: each <Type>PubSubType turns auto_fill_type_object and auto_fill_type_information
#      off and registers nothing; endpoints match by type name, as with every other vendor.
#      Reasons: Fast DDS 2.9 writes PID_TYPE_INFORMATION of its readers as encapsulated XCDR1
#      where XTypes 1.3 (7.6.3.2.2) asks for XCDR2, so CycloneDDS 0.10 rejects the whole
#      SubscriptionBuiltinTopicData ("pid 75 (TYPE_INFORMATION) invalid") and never matches the
#      reader; and a Fast DDS 2.9 participant that receives a COMPLETE TypeObject builds a
#      DynamicType from it on its receive thread, racing any other use of the (not thread-safe)
#      TypeObjectFactory in the process: crashes and "DYN_TYPES Error" lines on stdout.
#    - ON: each <Type>PubSubType registers the type objects (they must exist when the type is
#      registered with a participant) and announces both, as fastddsgen's default does, for
#      Fast DDS tools that discover types (Fast DDS Spy, DDS Record & Replay).
#
# Every pattern is checked: a fastddsgen that generates something else fails the build here
# instead of silently keeping the per-sample cost.
#
# Usage: cmake -DDIR=<output dir> -DNAME=<idl base name> -DTYPE_OBJECTS=ON|OFF -P this

foreach(var DIR NAME TYPE_OBJECTS)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "patch_generated.cmake: ${var} is not set")
  endif()
endforeach()

set(register "register${NAME}Types")

function(replace_checked file from to expected_count)
  file(READ "${file}" text)
  # Counted through a marker: matches themselves may hold ';', which CMake lists split on.
  string(REGEX REPLACE "${from}" "@teejet-match@" marked "${text}")
  string(REGEX MATCHALL "@teejet-match@" found "${marked}")
  list(LENGTH found count)
  if(expected_count STREQUAL "any")
    if(count EQUAL 0)
      message(FATAL_ERROR "${file}: pattern '${from}' not found; fastddsgen output changed")
    endif()
  elseif(NOT count EQUAL expected_count)
    message(FATAL_ERROR "${file}: pattern '${from}' found ${count} times, expected "
                        "${expected_count}; fastddsgen output changed")
  endif()
  string(REGEX REPLACE "${from}" "${to}" text "${text}")
  file(WRITE "${file}" "${text}")
  set(replaced ${count} PARENT_SCOPE)
endfunction()

# 1a. The data types' constructors stop registering.
replace_checked("${DIR}/${NAME}.cxx" "\n    // Just to register all known types\n    ${register}\\(\\);\n"
                "\n" any)
set(types ${replaced})
file(READ "${DIR}/${NAME}.cxx" text)
string(FIND "${text}" "${register}();" left)
if(NOT left EQUAL -1)
  message(FATAL_ERROR "${DIR}/${NAME}.cxx: ${register}() is still called")
endif()

# 1b. Registration runs its body once per process.
replace_checked("${DIR}/${NAME}TypeObject.cxx" "\nvoid ${register}\\(\\)\n\\{"
                "\nstatic void register_every_type()\n{" 1)
file(APPEND "${DIR}/${NAME}TypeObject.cxx" "
// Added by idl/patch_generated.cmake: the type objects are registered once per process.
void ${register}()
{
    static std::once_flag once;
    std::call_once(once, register_every_type);
}
")
replace_checked("${DIR}/${NAME}TypeObject.cxx" "\n#include <utility>\n" "\n#include <mutex>\n#include <utility>\n" 1)

# 2. Each PubSubType constructor either registers the type objects or announces no type.
if(TYPE_OBJECTS)
  set(announce "\n        ${register}(); // idl/patch_generated.cmake: TYPE_OBJECTS ON")
  replace_checked("${DIR}/${NAME}PubSubTypes.cxx" "(\n#include \"${NAME}PubSubTypes.h\"\n)"
                  "\\1#include \"${NAME}TypeObject.h\"\n" 1)
else()
  string(CONCAT announce
         "\n        auto_fill_type_object(false); // idl/patch_generated.cmake: TYPE_OBJECTS OFF"
         "\n        auto_fill_type_information(false);")
endif()
replace_checked("${DIR}/${NAME}PubSubTypes.cxx"
                "(\n        setName\\(\"[A-Za-z0-9_:]+\"\\);)"
                "\\1${announce}" ${types})

# 3. fastcdr's Cdr.h before the type-object header's `using namespace eprosima::fastrtps::types`:
#    seen after it, Cdr.h's `m_endianness == endianness` also finds TypesBase.h's reversed
#    operator==(T, const ReturnCode_t&), which clang (C++20) rejects as ambiguous.
replace_checked("${DIR}/${NAME}TypeObject.h" "\n#include <fastrtps/types/TypeObject.h>\n"
                "\n#include <fastcdr/Cdr.h>\n#include <fastrtps/types/TypeObject.h>\n" 1)

# 4. The type support of each type, found from the type (fastddsgen names it <Type>PubSubType and
#    says so nowhere a template can read): code generic over the types (topics, writers, readers,
#    the recorder's catalog) needs no line per type.
file(READ "${DIR}/${NAME}PubSubTypes.h" text)
string(REGEX MATCHALL "class [A-Za-z0-9_]+PubSubType : public eprosima::fastdds::dds::TopicDataType"
       declared "${text}")
if(NOT declared)
  message(FATAL_ERROR "${DIR}/${NAME}PubSubTypes.h: no <Type>PubSubType class; fastddsgen output changed")
endif()
set(traits "\n// Added by idl/patch_generated.cmake: each type's type support, for generic code.\nnamespace teejet\n{\n    template <class Type>\n    struct PubSubTypeOf;\n")
foreach(declaration ${declared})
  string(REGEX REPLACE "class ([A-Za-z0-9_]+)PubSubType : .*" "\\1" type "${declaration}")
  string(APPEND traits "    template <>\n    struct PubSubTypeOf<${type}>\n    {\n        using type = ${type}PubSubType;\n    };\n")
endforeach()
string(APPEND traits "}\n")
replace_checked("${DIR}/${NAME}PubSubTypes.h" "(\n#endif // _FAST_DDS_GENERATED_[A-Z0-9_]+_PUBSUBTYPES_H_)"
                "${traits}\\1" 1)
