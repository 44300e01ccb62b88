;;;; Seed 003: "Pepper robot shopping assistant" (a plain text page). The user builds two ROS
;;;; packages of their own, cram_pepper_description and cram_pepper_demo, file by file; their
;;;; files are written into a workspace under /tmp as the page says, found on ROS_PACKAGE_PATH
;;;; and loaded with ROS-LOAD:LOAD-SYSTEM, so that the user's packages (not cram-plans' built-in
;;;; ones) run. `roslaunch pepper_description upload.launch' is launch/pepper.launch on a
;;;; private master. Code the page has the user paste into a file is written into that file and
;;;; compiled (loaded) as the page's "compile" asks; the page's edits of a function (fragments
;;;; that replace part of it) are applied to the function's forms; REPL steps are replayed.
;;;;
;;;; Completions (page errors, not cut lines):
;;;;  - block 46, line 3: the page elides the body of spawn-products-one with "….."; the
;;;;    completion is the page's own body of that function (block 36), computed from the page.
;;;;  - block 59, line 7: "(let* '((?productname nil)" quotes the binding list (a compile error:
;;;;    QUOTE bound as a variable); the page's previous and next revisions of the function have
;;;;    "(let* ((?productname nil)".

(require :sb-posix)
(require :sb-bsd-sockets)

(in-package :seeds)

(defparameter *blocks-003*
  '((56 80) (84 89) (97 100) (114 114) (118 119) (123 126) (130 134) (138 139) (147 147)
    (193 208) (214 217) (227 239) (249 254) (262 301) (308 415) (421 468) (476 476)
    (484 484) (488 488 492 492) (516 571) (575 578) (586 638) (648 653) (657 657) (665 665)
    (669 669 673 673) (677 746) (747 749) (753 791) (797 818) (822 822) (830 830) (836 836 840 840)
    (852 854 858 861) (865 867) (875 917) (921 921) (931 936) (944 944) (952 955) (959 959 963 966)
    (974 977) (981 981 985 988) (994 1010) (1014 1019) (1023 1034) (1038 1038) (1046 1060)
    (1066 1073) (1079 1109) (1119 1225) (1231 1231 1235 1238) (1242 1242 1246 1255) (1263 1307) (1313 1317)
    (1323 1333) (1339 1345) (1351 1358) (1362 1396) (1402 1402) (1406 1435) (1443 1486)
    (1490 1490) (1494 1498) (1502 1526) (1532 1534) (1538 1542) (1546 1563) (1567 1571)
    (1575 1601) (1605 1614) (1618 1619) (1623 1627) (1630 1649) (1653 1654) (1658 1659)
    (1665 1670) (1674 1677) (1683 1686) (1690 1698) (1702 1703) (1707 1711) (1717 1722)
    (1726 1735) (1741 1744) (1748 1753))
  "The page's code blocks (files, file fragments, REPL steps) as page line ranges: (FROM TO ...)
pairs; a REPL step and the output the page shows for it leave out the prose between them.")

(define-seed "003" :format :plain
  :blocks (mapcar (lambda (r) (loop for (from to) on r by #'cddr append (lines-block lines from to)))
                  *blocks-003*))

(defun block-of-line (line)
  "The 1-based index of the block starting at page LINE."
  (1+ (or (position line *blocks-003* :key #'first)
          (error "no block of seed 003 starts at page line ~d" line))))

(defun page-range (from to)
  "The page's text of lines FROM to TO."
  (format nil "~{~a~^~%~}" (mapcar #'cdr (lines-block (seed-lines *seed*) from to))))

;;; ------------------------------------------------------------------------------------------
;;; The user's workspace: ~/workspace/ros/src/cram/cram_pepper/{cram_pepper_description,cram_pepper_demo}

(defvar *ws* (format nil "/tmp/cram-seed-003-ws-~d/" (sb-posix:getpid)))
(push (lambda () (uiop:delete-directory-tree (uiop:ensure-directory-pathname *ws*) :validate t
                                                                                    :if-does-not-exist :ignore))
      sb-ext:*exit-hooks*)
(sb-posix:setenv "ROS_PACKAGE_PATH"
                 (format nil "~aros/src:~a" *ws* (or (uiop:getenv "ROS_PACKAGE_PATH") "")) 1)

(defun pkg-file (pkg relpath)
  (merge-pathnames relpath (format nil "~aros/src/cram/cram_pepper/~a/" *ws* pkg)))

(defun write-user-file (pkg relpath text)
  "Write TEXT as the user's file RELPATH of package PKG (replacing it)."
  (let ((file (pkg-file pkg relpath)))
    (ensure-directories-exist file)
    (with-open-file (out file :direction :output :if-exists :supersede :external-format :utf-8)
      (write-string text out) (terpri out))
    file))

(defun read-forms (text package)
  "The forms of TEXT read in PACKAGE."
  (let ((*package* (find-package package)) (forms '()) (pos 0))
    (loop (multiple-value-bind (form end) (read-from-string text nil text :start pos)
            (when (eq form text) (return (nreverse forms)))
            (push form forms) (setf pos end)))))

;;; The demo's growing files: each a list of (key . text) chunks; a definition replaces the
;;; chunk of the same name, or is appended (or put after the IN-PACKAGE line: "at the top").

(defvar *chunks* (make-hash-table :test 'equal))

(defun chunk-key (form)
  (if (and (consp form) (member (car form) '(defun defparameter defvar defmacro def-fact-group)
                                :test (lambda (a b) (string= (string a) (string b)))))
      (list (string (first form)) (string (second form)))
      form))

(defun print-form (form)
  (let ((*package* (find-package :demo)) (*print-case* :downcase) (*print-pretty* t)
        (*print-right-margin* 100))
    (prin1-to-string form)))

(defun add-chunks (file text &key top)
  "Put the definitions of TEXT (page text or a form) into the demo's FILE, and write it."
  (let ((forms (if (stringp text) (read-forms text :demo) (list text))))
    (dolist (form (if top (reverse forms) forms))
      (let* ((key (chunk-key form))
             (chunk (cons key (if (and (stringp text) (= 1 (length forms))) text (print-form form))))
             (old (gethash file *chunks*))
             (at (position key old :key #'car :test #'equal)))
        (setf (gethash file *chunks*)
              (cond (at (let ((new (copy-list old))) (setf (nth at new) chunk) new))
                    (top (cons (first old) (cons chunk (rest old))))
                    (t (append old (list chunk))))))))
  (write-user-file "cram_pepper_demo" (format nil "src/~a" file)
                   (format nil "~{~a~^~%~%~}" (mapcar #'cdr (gethash file *chunks*)))))

(defun compile-user-file (file)
  "Compile and load the demo's FILE, as the page's \"compile\" (C-c C-k) does."
  (let ((path (pkg-file "cram_pepper_demo" (format nil "src/~a" file))))
    (multiple-value-bind (fasl warnings-p failure-p)
        (handler-bind ((warning #'muffle-warning))
          (compile-file path :output-file (format nil "/tmp/cram-seed-003-~d-~a.fasl"
                                                  (sb-posix:getpid) (pathname-name path))))
      (declare (ignore warnings-p failure-p))
      (expect fasl "~a does not compile" path)
      (handler-bind ((warning #'muffle-warning)) (load fasl))
      (delete-file fasl)
      path)))

(defun demo-form (key)
  "The form of the definition KEY (e.g. \"interaction\") of the demo's files."
  (loop for chunks being the hash-values of *chunks*
        do (let ((c (find (list "DEFUN" (string-upcase key)) chunks :key #'car :test #'equal)))
             (when c (return (first (read-forms (cdr c) :demo)))))))

;;; ------------------------------------------------------------------------------------------
;;; Checks

(defun d (name) (or (find-symbol (string name) :demo) (error "no symbol ~a in DEMO" name)))
(defun call (name &rest args) (apply (d name) args))
(defun obj (name) (btr:object (world) name))
(defun pepper () (btr:get-robot-object))
(defun joint (name) (btr:joint-state (pepper) name))
(defun joints-at (states tol)
  "The robot's joints have the values of STATES ((name value) ...), each within TOL."
  (every (lambda (s) (<= (abs (- (joint (first s)) (second s))) tol)) states))

(defun fold (s)
  (string-upcase (format nil "~{~a~^ ~}" (remove "" (uiop:split-string (string-trim " " s)
                                                                        :separator '(#\Space #\Newline #\Tab))
                                                 :test #'string=))))

(defun printed-like (value shown &key (package :demo))
  "VALUE printed in PACKAGE reads as the page's SHOWN text up to the first object address ({)."
  (let* ((p (fold (let ((*package* (find-package package))) (prin1-to-string value))))
         (s (fold shown))
         (n (or (position #\{ s) (length s))))
    (expect (and (>= (length p) n) (string= s p :end1 n :end2 n))
            "printed ~s, the page shows ~s" (subseq p 0 (min (length p) 120)) (subseq s 0 (min n 120)))))

(defmacro with-typed-input ((text) &body body)
  "Run BODY with TEXT as what the user types at the REPL ((read t) reads *TERMINAL-IO*)."
  `(let* ((in (make-string-input-stream ,text))
          (*terminal-io* (make-two-way-stream in *standard-output*))
          (*standard-input* in))
     ,@body))

(defun run-captured (thunk)
  "Call THUNK; (values its value and everything it printed)."
  (let* ((out (make-string-output-stream))
         (value (let ((*standard-output* (make-broadcast-stream *standard-output* out)))
                  (funcall thunk))))
    (values value (get-output-stream-string out))))

(defun same-forms-p (text file-text package)
  "The forms of TEXT occur, in this order, among the forms of FILE-TEXT."
  (flet ((printed (forms) (let ((*package* (find-package package)))
                            (mapcar #'prin1-to-string forms))))
    (let ((forms (printed (read-forms file-text package))))
      (every (lambda (f) (member f forms :test #'string=)) (printed (read-forms text package))))))

(defun occurs-in (form tree)
  "FORM occurs (EQUAL) somewhere in TREE."
  (or (equal form tree)
      (and (consp tree) (or (occurs-in form (car tree)) (occurs-in form (cdr tree))))))

(defun shelf-names () (mapcar #'btr:name (btr:rigid-bodies (btr:get-environment-object))))

;;; Edits of functions, on forms

(defun subst-form (new old tree)
  (cond ((equal tree old) new)
        ((consp tree) (cons (subst-form new old (car tree)) (subst-form new old (cdr tree))))
        (t tree)))

(defun insert-after (new anchor tree)
  "TREE with the forms NEW spliced in after the first element of a list EQUAL to ANCHOR."
  (cond ((atom tree) tree)
        ((equal (car tree) anchor) (cons (car tree) (append new (cdr tree))))
        (t (cons (insert-after new anchor (car tree)) (insert-after new anchor (cdr tree))))))

(defun find-list (pred tree)
  (cond ((atom tree) nil)
        ((funcall pred tree) tree)
        (t (or (find-list pred (car tree)) (find-list pred (cdr tree))))))

(defun define-demo (file form)
  "Put the definition FORM into the demo's FILE and compile it."
  (add-chunks file form)
  (compile-user-file file))

(load (merge-pathnames "seed-003-blocks.lisp" cl-user::*seed-directory*))
(load (merge-pathnames "seed-003-blocks-2.lisp" cl-user::*seed-directory*))
(stop-private-ros)
(finish-seed)
