"""Robot descriptions: URDF from xacro, as roslaunch's ``param command="xacro ..."`` makes it."""
