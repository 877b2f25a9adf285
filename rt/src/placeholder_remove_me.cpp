namespace ugv::rt {}
