# Writes the calls of the geodex.v1.Geodex service as a C macro list, read
# from the .proto itself, so that the proto is the one place a call is listed:
# the server's streamed calls and the C++ client's connection, its gRPC and
# retrying forms, its mock and the HTTP/JSON gateway's routes all expand from
# it, and a new call is its rpc line in geodex.proto.
#
#   cmake -DPROTO=geodex.proto -DOUT=geodex_rpcs.h -P rpc_list.cmake
#
# The list, in the order of the service:
#
#   #define GEODEX_V1_RPCS(X, ...)  X(Name, Request, Response, Kind, __VA_ARGS__) ...
#
# Request and Response are message names of geodex.v1; Kind is Unary,
# ServerStreaming or BidiStreaming. The trailing arguments are handed on to
# every X untouched, which lets a user pick calls by kind (token-paste Kind)
# and pass its own macro through. A declaration this script does not read
# (a client-streaming call, a message of another package, an rpc it cannot
# parse) stops the build with the reason: no user of the list knows it.

cmake_policy(VERSION 3.20)
if(NOT PROTO OR NOT OUT)
  message(FATAL_ERROR "rpc_list.cmake: give -DPROTO=<file.proto> -DOUT=<header>")
endif()
file(READ "${PROTO}" _text)
# Comments out first: they may name "rpc" or hold parentheses.
string(REGEX REPLACE "//[^\n]*" "" _text "${_text}")
string(REGEX REPLACE "/\\*([^*]|\\*+[^*/])*\\*+/" "" _text "${_text}")
string(REGEX REPLACE "[\r\n\t]" " " _text "${_text}")

string(REGEX MATCHALL "service +[A-Za-z0-9_]+ *\\{" _services "${_text}")
list(LENGTH _services _service_count)
if(NOT _service_count EQUAL 1 OR NOT _services MATCHES "service +Geodex *\\{")
  message(FATAL_ERROR "rpc_list.cmake: ${PROTO} must declare one service, Geodex; found: ${_services}")
endif()
string(REGEX REPLACE ".*service +Geodex *\\{" "" _body "${_text}")
# The service ends at its first "}". A "{" before it opens an rpc's option
# block, which this script does not read: refused.
string(REGEX REPLACE "\\}.*" "" _body "${_body}")
if(_body MATCHES "\\{")
  message(FATAL_ERROR "rpc_list.cmake: rpc option blocks are not read; declare each rpc with ';'")
endif()

# ";" separates CMake's list items: each declaration's ends in "|" instead.
string(REPLACE ";" "|" _body "${_body}")
string(REGEX MATCHALL "rpc [^|]*\\|" _rpcs "${_body}")
string(REGEX MATCHALL "rpc " _rpc_words "${_body}")
list(LENGTH _rpcs _rpc_count)
list(LENGTH _rpc_words _rpc_word_count)
if(NOT _rpc_count EQUAL _rpc_word_count OR _rpc_count EQUAL 0)
  message(FATAL_ERROR "rpc_list.cmake: ${PROTO}: could not split the service into rpc declarations")
endif()

set(_name "[A-Za-z_][A-Za-z0-9_]*")
set(_lines "")
foreach(_rpc IN LISTS _rpcs)
  string(REPLACE "|" ";" _declaration "${_rpc}")
  if(NOT _rpc MATCHES "^rpc +(${_name}) *\\( *(stream +)?(${_name}) *\\) *returns *\\( *(stream +)?(${_name}) *\\) *\\|$")
    message(FATAL_ERROR "rpc_list.cmake: cannot read \"${_declaration}\" (only messages of "
                        "geodex.v1, by their plain names)")
  endif()
  set(_call "${CMAKE_MATCH_1}")
  set(_request "${CMAKE_MATCH_3}")
  set(_response "${CMAKE_MATCH_5}")
  if(CMAKE_MATCH_2 AND CMAKE_MATCH_4)
    set(_kind BidiStreaming)
  elseif(CMAKE_MATCH_4)
    set(_kind ServerStreaming)
  elseif(CMAKE_MATCH_2)
    message(FATAL_ERROR "rpc_list.cmake: ${_call} is client-streaming, which neither the server "
                        "nor the client lists; make it bidirectional or unary")
  else()
    set(_kind Unary)
  endif()
  string(APPEND _lines "  X(${_call}, ${_request}, ${_response}, ${_kind}, __VA_ARGS__) \\\n")
endforeach()

get_filename_component(_proto_name "${PROTO}" NAME)
set(_header "#pragma once\n
// Generated from ${_proto_name} by proto/rpc_list.cmake: do not edit.
// The calls of geodex.v1.Geodex in the order of the service:
// X(Name, Request, Response, Kind, ...), Kind one of Unary, ServerStreaming,
// BidiStreaming; the arguments after X are handed on to every X.

#define GEODEX_V1_RPCS(X, ...) \\\n${_lines}
")
# Rewrite only a changed list, so that a comment edited in the proto does not
# rebuild every file that includes it.
set(_old "")
if(EXISTS "${OUT}")
  file(READ "${OUT}" _old)
endif()
if(NOT _old STREQUAL _header)
  file(WRITE "${OUT}" "${_header}")
endif()
