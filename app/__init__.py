"""poselifter app"""
