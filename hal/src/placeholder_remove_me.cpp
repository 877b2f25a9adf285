namespace ugv::hal {}
