"""The operator's view: a Meshcat page of the robot, its maps, scans and plans (rviz's role) and
the goal panel (the rqt goal plugin's role), for live runs (`--view`), recordings
(`--save-html`) and bag playback (`bag play --view`: view/bag_replay.py). Imported only when
asked for, so headless runs never create a Meshcat."""
