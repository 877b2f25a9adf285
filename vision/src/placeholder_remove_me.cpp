namespace ugv::vision {}
