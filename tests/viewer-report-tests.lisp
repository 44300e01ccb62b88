;;;; Tests of the viewer's /report endpoint (the page's test hook): it keeps a bounded number
;;;; of bounded texts, so no local process can grow the image through it.

(defpackage :cram-viewer-report-tests
  (:use :cl :fiveam))

(in-package :cram-viewer-report-tests)

(def-suite viewer-report :in cram-plans-tests:all
  :description "The viewer's /report endpoint is bounded.")
(in-suite viewer-report)

(defun post (url path body)
  "POST BODY (a string) to PATH of the server at URL; return the HTTP status code."
  (let* ((start (+ (search "//" url) 2))
         (colon (position #\: url :start start))
         (port (parse-integer url :start (1+ colon) :junk-allowed t))
         (socket (make-instance 'sb-bsd-sockets:inet-socket :type :stream :protocol :tcp)))
    (sb-bsd-sockets:socket-connect socket #(127 0 0 1) port)
    (unwind-protect
         (let ((stream (sb-bsd-sockets:socket-make-stream socket :input t :output t
                                                                 :external-format :latin-1
                                                                 :buffering :full)))
           (format stream "POST ~a HTTP/1.0~c~cHost: 127.0.0.1~c~cContent-Type: application/json~c~c~
                           Content-Length: ~d~c~c~c~c~a"
                   path #\Return #\Newline #\Return #\Newline #\Return #\Newline
                   (length body) #\Return #\Newline #\Return #\Newline body)
           (finish-output stream)
           (let ((status-line (read-line stream nil "")))
             (parse-integer status-line :start (1+ (position #\Space status-line)) :junk-allowed t)))
      (sb-bsd-sockets:socket-close socket))))

(test report-keeps-only-the-newest-few
  (let ((url (cram-viewer:viewer :port 0 :stream nil)))
    (unwind-protect
         (progn
           (setf cram-viewer::*reports* '())
           (dotimes (i (+ 3 cram-viewer::*max-reports*))
             (is (= 200 (post url "/report" (format nil "{\"n\": ~d}" i)))))
           (is (= cram-viewer::*max-reports* (length cram-viewer::*reports*)))
           (is (string= (format nil "{\"n\": ~d}" (+ 2 cram-viewer::*max-reports*))
                        (first cram-viewer::*reports*))
               "the newest first")
           ;; a body larger than the limit is refused, and not kept
           ;; (the server's threads see the global value: set it, then put it back)
           (let ((before (copy-list cram-viewer::*reports*))
                 (limit cram-viewer::*max-report-bytes*))
             (unwind-protect
                  (progn
                    (setf cram-viewer::*max-report-bytes* 100)
                    (is (= 413 (post url "/report" (make-string 200 :initial-element #\x))))
                    (is (equal before cram-viewer::*reports*))
                    (is (= 200 (post url "/report" (make-string 100 :initial-element #\y))))
                    (is (= 100 (length (first cram-viewer::*reports*)))))
               (setf cram-viewer::*max-report-bytes* limit))))
      (cram-viewer:stop-viewer)
      (setf cram-viewer::*reports* '()))))

(test recorded-costmaps-are-bounded
  ;; every overlay that notes a location designator's costmap counts against
  ;; *MAX-RECORDED-COSTMAPS*: beyond it the oldest overlays lose their costmap, not their samples
  (let ((cram-viewer::*overlays-with-costmaps* '())
        (cram-viewer::*max-recorded-costmaps* 4)
        (overlays (loop for i below 7
                        collect (let ((h (make-hash-table :test 'equal)))
                                  (setf (gethash "costmap" h) (list :costmap i)
                                        (gethash "samples" h) (list i))
                                  h))))
    (sb-thread:with-mutex (cram-viewer::*recorder-lock*)
      (mapc #'cram-viewer::keep-overlay-costmap overlays))
    (is (= 4 (length cram-viewer::*overlays-with-costmaps*)))
    (is (equal '(nil nil nil) (mapcar (lambda (o) (gethash "costmap" o)) (subseq overlays 0 3))))
    (is (equal '((:costmap 3) (:costmap 4) (:costmap 5) (:costmap 6))
               (mapcar (lambda (o) (gethash "costmap" o)) (subseq overlays 3))))
    (is (equal '((0) (1) (2)) (mapcar (lambda (o) (gethash "samples" o)) (subseq overlays 0 3))))))

(test deferred-designator-texts-are-the-designators-texts
  ;; a location overlay keeps its designator's text for later: printed when asked for, it is
  ;; what the designator printed at once would have been, in the package of that moment
  (let* ((pose (cl-transforms-stamped:make-pose-stamped
                "map" 0.0 (cl-transforms:make-3d-vector 1.5 -0.25 0.8)
                (cl-transforms:make-quaternion 0 0 0.6 0.8)))
         (designators
           (list (desig:make-designator :location `((:pose ,pose)))
                 (desig:make-designator :location `((:on ,(desig:make-designator
                                                           :object '((:type :counter-top))))
                                                    (:for ,(desig:make-designator
                                                            :object '((:type :bottle) (:name bottle-1))))
                                                    (:side (:left :right))))
                 (desig::%make-designator :location '((:reachable-for :pr2)) :quantifier :all))))
    (dolist (d designators)
      (let ((deferred (let ((*package* (find-package :cl-user)))
                        (cram-viewer::defer-designator-text d))))
        (is (not (stringp deferred)) "nothing printed yet")
        (let ((expected (let ((*package* (find-package :cl-user))) (cpl::designator-string d)))
              (text (let ((*package* (find-package :keyword)) (*print-case* :downcase))
                      (cram-viewer::overlay-designator-text deferred))))
          (is (string= expected text) "~a~%is not~%~a" text expected)
          (is (eq text (cram-viewer::overlay-designator-text deferred)) "printed once"))))
    (is (string= "text" (cram-viewer::overlay-designator-text "text")))
    (is (null (cram-viewer::overlay-designator-text nil)))))

(test viewer-url-follows-the-listening-socket
  (unwind-protect
       (let ((first (cram-viewer:viewer :port 0 :stream nil)))
         (flet ((port-url ()
                  (format nil "http://~a:~d/" (hunchentoot:acceptor-address cram-viewer::*acceptor*)
                          (usocket:get-local-port
                           (hunchentoot::acceptor-listen-socket cram-viewer::*acceptor*)))))
           (is (string= (port-url) first))
           (is (string= first (cram-viewer:viewer-url)))
           (is (eq (cram-viewer:viewer-url) (cram-viewer:viewer-url)) "made once")
           (cram-viewer:stop-viewer)
           (is (null (cram-viewer:viewer-url)))
           (let ((second (cram-viewer:viewer :port 0 :stream nil)))
             (is (string= (port-url) second) "a new socket: its own port")
             (is (string= second (cram-viewer:viewer-url))))))
    (cram-viewer:stop-viewer)))

(defparameter *two-visual-urdf*
  "<robot name=\"lamp\">
     <material name=\"red\"><color rgba=\"1 0 0 1\"/></material>
     <link name=\"base\"><visual><geometry><box size=\"0.2 0.2 0.1\"/></geometry></visual></link>
     <link name=\"arm\">
       <visual><geometry><box size=\"0.05 0.05 0.4\"/></geometry><material name=\"red\"/></visual>
       <visual><origin xyz=\"0 0 0.2\"/><geometry><sphere radius=\"0.05\"/></geometry></visual></link>
     <link name=\"bare\"/>
     <joint name=\"tilt\" type=\"revolute\"><parent link=\"base\"/><child link=\"arm\"/>
       <axis xyz=\"0 1 0\"/><limit lower=\"-1\" upper=\"1\" velocity=\"1\" effort=\"1\"/></joint>
     <joint name=\"fix\" type=\"fixed\"><parent link=\"arm\"/><child link=\"bare\"/></joint>
   </robot>")

(test link-colours-are-each-drawn-links-colour-once
  (let ((w (make-instance 'btr:bt-reasoning-world)))
    (btr:add-object w :urdf :lamp '((0 0 0) (0 0 0 1)) :urdf *two-visual-urdf*)
    (let* ((lamp (btr:object w :lamp))
           (d (cram-viewer::model-description lamp))
           (colours (cram-viewer::link-colours lamp d))
           (drawn (remove-duplicates (mapcar #'first (getf d :visuals)) :from-end t)))
      (is (= 3 (length (getf d :visuals))) "two visuals of the arm, one of the base")
      (is (= 2 (length colours)) "one colour per drawn link: ~s" colours)
      (is (equal (mapcar (lambda (i) (btr:object-color lamp i)) drawn) colours)))
    (btr:destroy-world w)))

(test a-change-wakes-the-threads-waiting-for-one
  ;; the live page's streams wait in WAIT-FOR-CHANGE; a change made while one waits wakes it
  ;; long before its timeout, and the waiter count is back to zero afterwards
  (let* ((before cram-viewer::*generation*)
         (result nil)
         (waiter (sb-thread:make-thread
                  (lambda ()
                    (let ((start (get-internal-real-time)))
                      (setf result (list (cram-viewer::wait-for-change before 30)
                                         (/ (- (get-internal-real-time) start)
                                            internal-time-units-per-second)))))
                  :name "viewer change waiter")))
    (loop repeat 500 until (plusp cram-viewer::*generation-waiters*) do (sleep 0.01))
    (is (= 1 cram-viewer::*generation-waiters*))
    (cram-viewer::bump-generation)
    (sb-thread:join-thread waiter)
    (is (= (1+ before) (first result)))
    (is (< (second result) 10))
    (is (zerop cram-viewer::*generation-waiters*))
    ;; nobody waits: a change is still counted
    (cram-viewer::bump-generation)
    (is (= (+ 2 before) cram-viewer::*generation*))))
