namespace ugv::ipc {}
