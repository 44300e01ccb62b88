;;;; The web server of the viewer (hunchentoot): the page, three.js from Debian's libjs-three,
;;;; the scene and state of the watched world, recorded runs, meshes, and live updates as
;;;; server-sent events.
;;;;
;;;; Live updates are server-sent events (EventSource): the traffic is one-way (belief state to
;;;; page), SSE is plain HTTP that hunchentoot serves with a thread per open page and no extra
;;;; library (Debian has no websocket server for hunchentoot), and the browser reconnects by
;;;; itself; long-polling would cost a request per update.  Each open page's thread wakes when
;;;; a motion is recorded (or every 0.1 s for changes made at the REPL), reads the world's poses
;;;; and joints in two batch calls, and sends only what changed.  With no page open nothing runs.

(in-package :cram-viewer)

(defvar *viewer-port* 8020 "Default port of the viewer.")
(defvar *viewer-host* "127.0.0.1" "Default address the viewer listens on (loopback).")
(defvar *acceptor* nil "The running hunchentoot acceptor, or NIL.")
(defvar *watched* nil "Weak pointer to the world the live page shows (NIL: the current one).")
(defvar *reports* '()
  "Test hook: JSON texts the page posted to /report, newest first; at most *MAX-REPORTS*.")
(defparameter *max-reports* 4 "How many /report texts *REPORTS* keeps (the newest).")
(defparameter *max-report-bytes* (* 8 1024 1024)
  "The largest /report body accepted, in bytes (the page's report may hold a PNG picture).")

(defun record-report ()
  "Keep the body of a POST to /report in *REPORTS* (the newest *MAX-REPORTS* of them); a body
longer than *MAX-REPORT-BYTES* (or of unknown length) is refused unread with status 413."
  (let ((length (ignore-errors (parse-integer (or (hunchentoot:header-in* :content-length) "")))))
    (cond ((or (null length) (> length *max-report-bytes*))
           (setf (hunchentoot:return-code*) hunchentoot:+http-request-entity-too-large+)
           (reply "text/plain" (format nil "a report is at most ~d bytes" *max-report-bytes*)))
          (t
           (let ((body (or (hunchentoot:raw-post-data :force-text t) "")))
             (setf *reports* (cons body (subseq *reports* 0 (min (length *reports*)
                                                                 (1- *max-reports*))))))
           (reply "text/plain" "ok")))))
(defvar *live-overlays* '() "Overlays of the live view (SHOW-COSTMAP, SHOW-POSES, SHOW-TARGET).")

(defun three-file (name)
  "The installed file of the three.js part NAME; an error naming it when libjs-three is missing."
  (let ((entry (assoc name *replay-three-files* :test #'string=)))
    (unless entry
      (error "viewer: ~s is not one of the three.js files ~{~a~^, ~}" name (mapcar #'car *replay-three-files*)))
    (or (probe-file (merge-pathnames (cdr entry) *replay-three-directory*))
        (error "viewer: ~a is missing: install Debian's libjs-three (make setup)"
               (merge-pathnames (cdr entry) *replay-three-directory*)))))

(defun asset-file (name)
  "A file of the page (viewer.js, viewer.css) in projection/viewer/."
  (asdf:system-relative-pathname "cram-plans/viewer" (format nil "projection/viewer/~a" name)))

(defun watched-world ()
  "The world the live page shows: the one given to VIEWER while it lives, else the current
belief state (the global value of BTR:*CURRENT-BULLET-WORLD*)."
  (let ((w (and *watched* (sb-ext:weak-pointer-value *watched*))))
    (if (and w (native:world-alive-p (btr:world-handle w)))
        w
        (symbol-value 'btr:*current-bullet-world*))))

;;; ---- overlays of the live view -------------------------------------------------------------------

(defun set-live-overlay (type overlay)
  (setf *live-overlays* (append (remove type *live-overlays* :key (lambda (o) (gethash "type" o))
                                                             :test #'equal)
                                (list overlay)))
  (bump-generation)
  overlay)

(defun show-costmap (location)
  "Show the costmap of LOCATION (a location designator or a COSTMAP:LOCATION-COSTMAP) as a heat
map on the floor of the live view, with the designator's first samples. Returns the costmap."
  (let* ((costmap (cond ((typep location 'costmap:location-costmap) location)
                        ((typep location 'desig:location-designator)
                         (or (costmap:designator-costmap location)
                             (error "SHOW-COSTMAP: ~s has no costmap (no DESIG-COSTMAP rule applies)" location)))
                        (t (error "SHOW-COSTMAP: ~s, expected a location designator or a location costmap"
                                  location))))
         (samples (and (typep location 'desig:location-designator)
                       (mapcar #'pose-stamped-list
                               (cut:force-ll (cut:lazy-take 30 (costmap:costmap-samples costmap)))))))
    (set-live-overlay "location" (obj "type" "location" "costmap" costmap "samples" samples
                                      "designator" (and (typep location 'desig:location-designator)
                                                        (cpl::designator-string location))))
    costmap))

(defun show-poses (poses &key chosen)
  "Show POSES (poses or pose-stamped in the map) as arrows on the live view; CHOSEN (one pose)
in green."
  (flet ((p (x) (if (typep x 'cl-transforms:pose) (pose-stamped-list x)
                    (error "SHOW-POSES: ~s is not a pose" x))))
    (set-live-overlay "location" (obj "type" "location" "costmap" nil
                                      "samples" (append (and chosen (list (p chosen))) (mapcar #'p poses))))))

(defun show-target (point)
  "Mark POINT ((x y z) or a pose) as the looking target on the live view."
  (let ((xyz (cond ((typep point 'cl-transforms:pose)
                    (subseq (pose-stamped-list point) 0 3))
                   ((and (listp point) (= 3 (length point)) (every #'realp point)) point)
                   (t (error "SHOW-TARGET: ~s, expected (x y z) or a pose" point)))))
    (set-live-overlay "target" (obj "type" "target" "point" xyz))))

(defun clear-overlays ()
  "Remove every overlay of the live view."
  (setf *live-overlays* '())
  (bump-generation)
  t)

(defun overlays () "The overlays of the live view." (copy-list *live-overlays*))

;;; ---- HTTP ---------------------------------------------------------------------------------------

(defclass viewer-acceptor (hunchentoot:acceptor) ()
  (:documentation "The viewer's acceptor: every request goes to SERVE."))

(defmethod hunchentoot:acceptor-dispatch-request ((acceptor viewer-acceptor) request)
  (declare (ignore request))
  (handler-case (serve (hunchentoot:script-name*))
    (error (e)
      (setf (hunchentoot:return-code*) 500
            (hunchentoot:content-type*) "text/plain; charset=utf-8")
      (format nil "viewer: ~a" e))))

(defmethod hunchentoot:acceptor-log-access ((acceptor viewer-acceptor) &key return-code)
  (declare (ignore return-code)))

(defun reply (content-type body)
  (setf (hunchentoot:content-type*) content-type)
  (setf (hunchentoot:header-out :cache-control) "no-cache")
  body)

(defun not-found (what)
  (setf (hunchentoot:return-code*) 404)
  (reply "text/plain; charset=utf-8" (format nil "viewer: ~a not found" what)))

(defun run-parameter ()
  (let* ((text (or (hunchentoot:get-parameter "run") ""))
         (id (ignore-errors (parse-integer text))))
    (or id (error "run ~s, expected a run number" text))))

(defun serve (path)
  "The reply to a GET of PATH."
  (cond ((string= path "/") (reply "text/html; charset=utf-8" (page-html :live)))
        ((string= path "/replay") (reply "text/html; charset=utf-8" (page-html :replay :run (run-parameter))))
        ((string= path "/viewer.js") (hunchentoot:handle-static-file (asset-file "viewer.js") "text/javascript"))
        ((string= path "/viewer.css") (hunchentoot:handle-static-file (asset-file "viewer.css") "text/css"))
        ((uiop:string-prefix-p "/three/" path)
         (let ((name (subseq path 7)))
           (if (assoc name *replay-three-files* :test #'string=)
               (hunchentoot:handle-static-file (three-file name) "text/javascript")
               (not-found path))))
        ((uiop:string-prefix-p "/mesh/" path)
         (let ((file (mesh-file (subseq path 6))))
           (if file (hunchentoot:handle-static-file file "application/octet-stream") (not-found path))))
        ((string= path "/scene.json") (reply "application/json" (live-scene-json (watched-world))))
        ((string= path "/runs.json") (reply "application/json" (json-string (runs-summary))))
        ((string= path "/run.json") (reply "application/json" (json-string (run-json (find-run (run-parameter))))))
        ((string= path "/events") (stream-events))
        ((string= path "/report") (record-report))
        (t (not-found path))))

(defun runs-summary ()
  (mapcar (lambda (r) (obj "id" (run-id r) "label" (run-label r)
                           "steps" (fill-pointer (run-steps r))
                           "failed" (count-if #'step-failed-p (run-steps r))))
          (recorded-runs)))

(defun live-scene-json (world)
  (multiple-value-bind (names v) (capture-state world)
    (declare (ignore v))
    (let ((descriptors (mapcar (lambda (n) (object-descriptor (btr:object world n))) names)))
      (json-string (obj "objects" descriptors
                        "meshes" (mesh-table (descriptor-meshes descriptors))
                        "state" (world-state world)
                        "overlays" (overlays-json *live-overlays*))))))

;;; ---- server-sent events ---------------------------------------------------------------------------

(defun send-event (stream event data)
  (let ((text (format nil "event: ~a~%data: ~a~%~%" event data)))
    (write-sequence (sb-ext:string-to-octets text :external-format :utf-8) stream)
    (force-output stream)))

(defun stream-events ()
  "Serve /events: a server-sent event stream with `scene' (the objects changed), `state' (poses
and joints changed), `overlays' and `runs' events, until the page goes away."
  (setf (hunchentoot:content-type*) "text/event-stream"
        (hunchentoot:header-out :cache-control) "no-cache")
  (let ((stream (hunchentoot:send-headers))
        (last-world nil) (last-names :none) (last-state nil) (last-runs nil)
        (generation -1) (overlay-generation -1) (idle 0))
    (handler-case
        (loop
          (let ((world (watched-world)))
            (multiple-value-bind (names state) (ignore-errors (capture-state world))
              (when state
                (cond ((or (not (eq world last-world)) (not (eq names last-names)))
                       (send-event stream "scene" (live-scene-json world))
                       (setf last-world world last-names names last-state state overlay-generation generation))
                      ((not (equalp state last-state))
                       (send-event stream "state" (json-string (world-state world)))
                       (setf last-state state)
                       (setf idle 0))))))
          (unless (= overlay-generation generation)
            (send-event stream "overlays" (json-string (overlays-json *live-overlays*)))
            (setf overlay-generation generation))
          (let ((runs (mapcar (lambda (r) (cons (run-id r) (fill-pointer (run-steps r)))) (recorded-runs))))
            (unless (equal runs last-runs)
              (send-event stream "runs" (json-string (runs-summary)))
              (setf last-runs runs)))
          (when (> (incf idle) 100)       ; a comment every ~10 s finds closed pages
            (send-event stream "ping" "{}")
            (setf idle 0))
          (setf generation (wait-for-change generation 0.1)))
      (error () nil))
    nil))

;;; ---- starting and stopping ----------------------------------------------------------------------

(defun viewer-running-p () "True when the viewer serves." (and *acceptor* (hunchentoot:started-p *acceptor*) t))

(defvar *viewer-url* (cons nil nil)
  "(listening socket . URL): the URL of the viewer last asked for, made once per socket (every
run's debug window prints it).")

(defun viewer-url ()
  "The URL of the running viewer, or NIL."
  (when (viewer-running-p)
    (let ((socket (hunchentoot::acceptor-listen-socket *acceptor*))
          (cached *viewer-url*))
      (if (and socket (eq (car cached) socket))
          (cdr cached)
          (let ((url (format nil "http://~a:~d/" (hunchentoot:acceptor-address *acceptor*)
                             (usocket:get-local-port socket))))
            (setf *viewer-url* (cons socket url))
            url)))))

(defun stop-viewer ()
  "Stop the viewer (open pages lose their connection)."
  (when *acceptor*
    (ignore-errors (hunchentoot:stop *acceptor* :soft nil))
    (setf *acceptor* nil *viewer-overlays-wanted* nil))
  t)

(defun try-start (host port)
  (let ((acceptor (make-instance 'viewer-acceptor :address host :port port
                                                  :access-log-destination nil
                                                  :message-log-destination nil)))
    (handler-case (progn (hunchentoot:start acceptor) acceptor)
      (usocket:address-in-use-error () nil))))

(defun start-viewer (&key (port *viewer-port* port-p) (host *viewer-host* host-p)
                          (world btr:*current-bullet-world*) (stream *standard-output*))
  "Start (or re-point) the viewer; see VIEWER. Returns the URL."
  (setf *watched* (sb-ext:make-weak-pointer world))
  (when (and (viewer-running-p)
             (or (and port-p (/= port (usocket:get-local-port (hunchentoot::acceptor-listen-socket *acceptor*))))
                 (and host-p (string/= host (hunchentoot:acceptor-address *acceptor*)))))
    (stop-viewer))
  (unless (viewer-running-p)
    (setf *acceptor*
          (or (try-start host port)
              (and (not port-p)
                   (loop for p from (1+ port) to (+ port 20) thereis (try-start host p)))
              (error "VIEWER: port ~d on ~a is in use~:[~; (and the next 20)~]" port host (not port-p)))
          *viewer-overlays-wanted* t))
  (bump-generation)
  (let ((url (viewer-url)))
    (when stream (format stream "~&Viewer of the belief state: ~a~%" url))
    url))
