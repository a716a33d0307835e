class NonlinearGreyBox:
    pass
