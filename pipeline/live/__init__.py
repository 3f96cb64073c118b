"""Live feeds: receive ASTERIX over UDP, keep the recent reports, record, replay, and monitor them."""
