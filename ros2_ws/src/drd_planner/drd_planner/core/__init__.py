"""ROS-free, FCL-free algorithms: problem model, DiRECt, BiSECt, decision tree, episodes, bounds."""
