# ctxfuse_gins_nav20: the GNSS/INS pipeline for Nav20 compiled once (gins_nav20.hpp), linked by
# the tests, bench_gins_drive and the tool. Included by each of their CMakeLists, so that it
# exists whichever of them the build has; defined by the first.
if(NOT TARGET ctxfuse_gins_nav20)
  add_library(ctxfuse_gins_nav20 STATIC ${CMAKE_CURRENT_LIST_DIR}/gins_nav20.cpp)
  target_include_directories(ctxfuse_gins_nav20 PUBLIC ${CMAKE_CURRENT_LIST_DIR})
  target_link_libraries(ctxfuse_gins_nav20 PUBLIC ctxfuse::ctxfuse PRIVATE ctxfuse_project_options)
endif()
