# What an install space (cmake --install, catkin_make install, the Debian package) holds: what a
# user runs on a robot or a base station without the source tree. Included last from the root
# CMakeLists.txt, once every target is defined. test/ros/install_space/ runs the launch files from
# such an install alone.

# The nodelet plugin and the image_transport subscribers (nodelet_plugins.xml names
# libstereo_fusion_nodelet, image_transport_plugins.xml libstereo_fusion_image_transport, which pluginlib finds in
# the prefix's library folder, lib/ or Debian's lib/x86_64-linux-gnu/), the library both link
# (libstereo_fusion_decode_reports) and the static libraries catkin_package() exports, so
# find_package(stereo_fusion) works from the install too.
install(TARGETS stereo_fusion_nodelet stereo_fusion_image_transport stereo_fusion_decode_reports
                stereo_fusion_core stereo_fusion_ros
        LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
        ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
        RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
install(DIRECTORY include/stereo_fusion/ DESTINATION ${CATKIN_PACKAGE_INCLUDE_DESTINATION})

# rosrun stereo_fusion <name>: the nodes (the standalone fusion node, the base station's
# assembler, the package's own nodelet manager) and the command-line tools the scripts run.
install(TARGETS stereo_fusion_node mesh_assembler_node stereo_fusion_manager
                stereo_fusion_fuse stereo_fusion_simulate stereo_fusion_evaluate stereo_fusion_evaluate_esdf
                stereo_fusion_texture_compare stereo_fusion_soak stereo_fusion_planning_probe
                stereo_fusion_parameters
        RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
# The demo's progress and bandwidth monitors (shebang /usr/bin/python3, Debian's ROS Python) and
# the demo itself on an installed package (rosrun stereo_fusion demo.sh).
catkin_install_python(PROGRAMS tools/demo/demo_monitor.py tools/demo/bandwidth_monitor.py
                      DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
install(PROGRAMS tools/demo/demo.sh DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
install(FILES tools/demo/demo_session.sh DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})  # demo.sh sources it

# $(find stereo_fusion)/...: the launch files, their default parameters, the rviz configurations and
# the plugin description package.xml exports (msg/srv and the generated code catkin installs itself).
install(FILES nodelet_plugins.xml image_transport_plugins.xml DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION})
install(DIRECTORY launch config rviz DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION})

# The rviz display stereo_fusion/Mesh, where it is built (librviz-dev found).
if(STEREO_FUSION_RVIZ_PLUGIN)
  install(TARGETS stereo_fusion_rviz LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION})
  install(FILES rviz_plugin.xml DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION})
endif()
