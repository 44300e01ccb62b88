;;;; The browser viewer: replay data of move-bottle, and the page itself in headless Chromium
;;;; (what it draws read back from the page: a report it posts to the server or writes into the
;;;; DOM, and its WebGL pixels).

(defpackage :cram-plans-tests/viewer
  (:use :cl :fiveam))

(in-package :cram-plans-tests/viewer)

(def-suite viewer :in cram-plans-tests:all :description "The browser viewer and replays.")
(in-suite viewer)

(defun chromium ()
  "The chromium executable, or NIL."
  (find-if #'probe-file '("/usr/bin/chromium" "/usr/bin/chromium-browser")))

(defun chromium-args (url &rest extra)
  (append (list (chromium) "--headless" "--no-sandbox" "--disable-gpu" "--use-gl=swiftshader"
                "--use-angle=swiftshader" "--enable-unsafe-swiftshader" "--hide-scrollbars"
                "--window-size=1280,800"
                (format nil "--user-data-dir=/tmp/cram-plans-chromium-~d" (sb-posix:getpid)))
          extra (list url)))

(defun run-chromium (url &rest extra)
  "Run headless Chromium on URL with EXTRA flags; its standard output."
  (with-output-to-string (out)
    (sb-ext:run-program (first (apply #'chromium-args url extra)) (rest (apply #'chromium-args url extra))
                        :output out :error nil :wait t)))

(defvar *move-bottle-run* nil "The recorded run of one move-bottle (made once).")

(defun move-bottle-run ()
  (or *move-bottle-run*
      (progn
        (btw-tut:init-projection)
        (let ((cpl:*log-stream* (make-broadcast-stream))) (btw-tut:move-bottle))
        (setf *move-bottle-run* (cram-viewer:last-run)))))

(defun get-in (table &rest keys)
  (reduce (lambda (h k) (and (hash-table-p h) (gethash k h))) keys :initial-value table))

(defun near (a b tolerance) (every (lambda (x y) (< (abs (- x y)) tolerance)) a b))

(test replay-records-one-step-per-motion
  "move-bottle records a run with a step after each motion of the task tree, the last with the
bottle on the island; its JSON names the kitchen, the PR2 and the bottle."
  (let* ((run (move-bottle-run))
         (steps (cram-viewer:run-steps run))
         (motions (cpl:find-task-tree-nodes (lambda (n) (eq (cpl:node-kind n) :motion))
                                            (cram-viewer:run-root run))))
    (is (> (length steps) 10))
    (is (= (length motions) (length steps)))
    (is (near (subseq (cram-viewer:step-object-pose run (aref steps (1- (length steps))) 'btw-tut::bottle-1) 0 3)
              '(-0.8 2.0 0.952) 0.03))
    (let* ((json (yason:parse (cram-viewer::json-string (cram-viewer:run-json run))))
           (names (mapcar (lambda (o) (gethash "name" o)) (gethash "objects" json))))
      (is (subsetp '("iai-kitchen" "pr2" "bottle-1") names :test #'string=))
      (is (= (length steps) (length (gethash "steps" json))))
      (is (string= "top-level" (get-in json "tree" "kind"))))))

(test viewer-bad-input
  "The viewer's entry points name the bad value."
  (signals error (btr:viewer :port "80"))
  (signals error (btr:viewer :world 42))
  (signals error (cram-viewer:find-run -5))
  (signals error (cram-viewer:write-replay "/tmp/x/" :run :nope)))

(defun save-data-url (url path)
  "Write the base64 PNG of the data URL URL to PATH."
  (let ((comma (position #\, url)))
    (with-open-file (out path :direction :output :element-type '(unsigned-byte 8) :if-exists :supersede)
      (write-sequence (cl-base64:base64-string-to-usb8-array (subseq url (1+ comma))) out))
    path))

(defun wait-for-report (seconds)
  (loop repeat (* 10 seconds)
        when cram-viewer::*reports* return (yason:parse (first cram-viewer::*reports*))
        do (sleep 0.1)))

(test live-page-in-chromium
  "The live page, loaded in headless Chromium, draws the kitchen, the PR2 and the bottle: its
own report lists them with meshes, its forward kinematics agrees with the shim, and its WebGL
picture is mostly drawn, with red (bottle) pixels when it looks at the bottle."
  (if (null (chromium))
      (skip "chromium is not installed (Debian package chromium; make setup installs it)")
      (let ((run (move-bottle-run)))
        (declare (ignore run))
        (setf cram-viewer::*reports* '())
        (let ((url (btr:viewer :port 0 :stream nil)))
          (unwind-protect
               (let* ((shot (format nil "/tmp/cram-plans-viewer-live-~d.png" (sb-posix:getpid)))
                      (process (sb-ext:run-program (chromium)
                                                   (rest (chromium-args (format nil "~a?report=1&image=1" url)))
                                                   :output nil :error nil :wait nil))
                      (report (unwind-protect (wait-for-report 40)
                                (when (sb-ext:process-alive-p process)
                                  (sb-ext:process-kill process 15)
                                  (sb-ext:process-wait process))
                                (sb-ext:process-close process))))
                 (is (not (null report)) "the page posted no report")
                 (when report (save-data-url (gethash "image" report) shot))
                 (when report
                   (dolist (name '("iai-kitchen" "pr2" "bottle-1"))
                     (is (get-in report "objects" name "visible") "~a is not visible" name)
                     (is (plusp (get-in report "objects" name "meshes")) "~a has no meshes" name))
                   (is (> (get-in report "objects" "iai-kitchen" "meshes") 50))
                   (let ((robot (btr:get-robot-object)))
                     (dolist (link '("r_gripper_tool_frame" "head_tilt_link" "torso_lift_link"))
                       (let ((shim (btr:link-pose robot link))
                             (page (get-in report "objects" "pr2" "links" link)))
                         (is (and page (near page (list (cl-transforms:x (cl-transforms:origin shim))
                                                        (cl-transforms:y (cl-transforms:origin shim))
                                                        (cl-transforms:z (cl-transforms:origin shim)))
                                             1d-3))
                             "link ~a: page ~a, shim ~a" link page shim))))
                   (is (> (get-in report "pixels" "drawn") 0.2))
                   (is (probe-file shot))))
            (cram-viewer:stop-viewer))))))

(defun dom-report (html)
  "The JSON report the page wrote into #cram-report of the dumped DOM HTML."
  (let* ((start (search "id=\"cram-report\"" html))
         (open (and start (position #\> html :start start)))
         (close (and open (search "</pre>" html :start2 open))))
    (and close (yason:parse (cram-viewer::html-unescape (subseq html (1+ open) close))))))

(test replay-from-disk-in-chromium
  "The replay written by WRITE-REPLAY opens from disk (file://, no server) in headless Chromium,
has one step per recorded motion, and its last step shows the bottle standing on the island."
  (if (null (chromium))
      (skip "chromium is not installed (Debian package chromium; make setup installs it)")
      (let* ((run (move-bottle-run))
             (dir (format nil "/tmp/cram-plans-replay-~d/" (sb-posix:getpid)))
             (html (cram-viewer:write-replay dir :run run))
             (report (dom-report (run-chromium (format nil "file://~a" (namestring html)) "--dump-dom"
                                                "--virtual-time-budget=20000"))))
        (is (probe-file (merge-pathnames "three/three.min.js" dir)))
        (is (not (null report)) "no report in the page's DOM")
        (when report
          (is (string= "replay" (gethash "mode" report)))
          (is (= (length (cram-viewer:run-steps run)) (gethash "steps" report)))
          (is (= (1- (gethash "steps" report)) (gethash "step" report)))
          (let ((bottle (get-in report "objects" "bottle-1" "box"))
                (island (get-in report "objects" "iai-kitchen" "links" "kitchen_island_surface")))
            (is (and bottle island) "bottle box ~a, island surface ~a" bottle island)
            (when (and bottle island)
              (destructuring-bind ((x0 y0 z0) (x1 y1 z1)) bottle
                (declare (ignore z1))
                (is (near (list (/ (+ x0 x1) 2) (/ (+ y0 y1) 2)) '(-0.8 2.0) 0.03))
                ;; the bottle stands on the island's top (0.851 m)
                (is (< (abs (- z0 0.851)) 0.02) "bottle bottom at ~,3f m" z0)
                (is (< (abs (- (/ (+ x0 x1) 2) (first island))) 0.6))
                (is (< (abs (- (/ (+ y0 y1) 2) (second island))) 1.2)))))))))
