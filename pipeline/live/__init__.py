"""Live feeds (issue 30): receive ASTERIX over UDP (``receive``), decode it in batches (``decode``) into a
thread-safe ``state.LiveState`` the monitor page reads, record it as pcapng (``record``) and replay any
recording as UDP (``replay``; a raw one framed as decode frames it: ``raw_blocks``); the monitor page
(``monitor``) shows the state with the live figures of ``health``."""
