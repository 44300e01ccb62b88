;;;; Entry points loaded with cram-plans: BTR:VIEWER and the DEBUG-WINDOW hook load the web
;;;; server (system cram-plans/viewer, hunchentoot) on first use, so projection without a viewer
;;;; loads and costs nothing of it.

(in-package :cram-viewer)

(defvar *start-viewer-from-debug-window*
  (not (member (uiop:getenv "CRAM_PLANS_VIEWER") '("0" "no" "off" "false") :test #'equalp))
  "When true, BTR:DEBUG-WINDOW starts the browser viewer on its world and prints the URL (there
is no X window to open). Environment: CRAM_PLANS_VIEWER=0 turns it off.")

(defun ensure-viewer-loaded ()
  "Load the system cram-plans/viewer (hunchentoot and the page) unless it is loaded."
  (unless (fboundp 'start-viewer)
    (let ((*standard-output* (make-broadcast-stream)))
      (asdf:load-system "cram-plans/viewer"))))

(defun viewer (&key (port nil port-p) (host nil host-p) (world btr:*current-bullet-world*)
                    (stream *standard-output*))
  "Serve the browser viewer of WORLD (default: the current belief state; any world, also a
copy) at http://HOST:PORT/ (defaults *VIEWER-HOST*, *VIEWER-PORT*; a busy default port moves to
the next free one) and print its URL to STREAM. The page draws the world with three.js, follows
it live, and replays the recorded projection runs. An already running viewer is pointed at
WORLD (and moved when PORT or HOST differ). Returns the URL."
  (unless (typep world 'btr:bt-reasoning-world)
    (error "VIEWER: world ~s, expected a BTR:BT-REASONING-WORLD" world))
  (when (and port-p (not (typep port '(integer 0 65535))))
    (error "VIEWER: port ~s, expected an integer from 0 to 65535" port))
  (when (and host-p (not (stringp host)))
    (error "VIEWER: host ~s, expected a string such as \"127.0.0.1\"" host))
  (ensure-viewer-loaded)
  (apply 'start-viewer :world world :stream stream
         (append (and port-p (list :port port)) (and host-p (list :host host)))))

(setf (fdefinition 'btr::viewer) #'viewer
      (documentation 'btr::viewer 'function) (documentation 'viewer 'function))

(defun debug-window-viewer (world)
  "The DEBUG-WINDOW hook: start (or point) the viewer at WORLD when
*START-VIEWER-FROM-DEBUG-WINDOW*, and print its URL (each call: the window of the tutorials
is this page)."
  (when *start-viewer-from-debug-window*
    (viewer :world world :stream *standard-output*)))

(setf btr::*debug-window-hook* 'debug-window-viewer)
