"""Grey-box models: linear GreyBox with greyest, NonlinearGreyBox, delays, estimation results."""
