namespace ugv::bringup {}
