"""Pages every visitor reaches: the guide for clinics (docs/GUIDE.md), the favicon, the 500 page."""
